"""Exported players in PyTorch: ``t2e.load_policy(folder)`` rebuilds the
actor of a checkpoint folder (from ``export``, or a training run's
``checkpoints/NAME``) and plays its side greedily, as the Rust controller
``ckpt:FOLDER`` does. PyTorch is imported only here, so the environment
itself needs no torch."""

from __future__ import annotations

import hashlib
import json
import math
import os
import stat
import struct
import weakref
from pathlib import Path
from typing import Dict, Optional

import numpy as np

FORMAT = 2
ACTIONS = 5
PATCH = 48
POSITION_SCALE = 8.0
MIN_DISTANCE = 1e-3
VECTOR_INPUTS = ("layer_norm", "scaled", "egocentric")
# How far a wall ray reads: a ray's number is its distance over this, at
# most 1 (WALL_RAY_RANGE_M in crates/core/src/env/sight.rs).
WALL_RAY_RANGE_M = 16.0
SIDES = ("captors", "target")


class PolicyError(ValueError):
    """A checkpoint folder that cannot be played: names the file and why."""


def _refuse(path: Path, reason: str) -> PolicyError:
    return PolicyError(f"{path}: {reason}")


def _read_safetensors(path: Path):
    """The tensors of a safetensors file, as torch tensors (float32 only)."""
    import torch

    data = path.read_bytes()
    if len(data) < 8:
        raise _refuse(path, "too short for a safetensors file")
    (n,) = struct.unpack("<Q", data[:8])
    if 8 + n > len(data):
        raise _refuse(path, "its header runs past the end of the file")
    try:
        header = json.loads(data[8 : 8 + n])
    except ValueError as e:
        raise _refuse(path, f"its header is not JSON ({e})") from None
    body = memoryview(data)[8 + n :]
    if not isinstance(header, dict):
        raise _refuse(path, "its header is not a JSON object")
    tensors = {}
    for name, entry in header.items():
        if name == "__metadata__":
            continue
        if not isinstance(entry, dict):
            raise _refuse(path, f"tensor {name}: its entry is not an object")
        if entry.get("dtype") != "F32":
            raise _refuse(path, f"tensor {name} is {entry.get('dtype')}, not F32")
        offsets, shape = entry.get("data_offsets"), entry.get("shape")
        if (
            not isinstance(offsets, list)
            or len(offsets) != 2
            or not all(isinstance(x, int) and x >= 0 for x in offsets)
            or not isinstance(shape, list)
            or not all(isinstance(x, int) and x >= 0 for x in shape)
        ):
            raise _refuse(path, f"tensor {name}: data_offsets {offsets!r} or shape {shape!r} malformed")
        start, end = offsets
        if end < start or end - start != 4 * math.prod(shape) or end > len(body):
            raise _refuse(path, f"tensor {name}: {end - start} bytes for shape {shape}")
        t = torch.frombuffer(bytearray(body[start:end]), dtype=torch.float32).reshape(shape)
        if not torch.isfinite(t).all():
            raise _refuse(path, f"tensor {name} holds non-finite weights")
        tensors[name] = t
    return tensors


# Bounds on what meta.json may ask for: the largest networks the Rust
# learners build are far below these; past them a tampered or foreign file
# would allocate gigabytes before any weight is read.
MAX_HIDDEN = 4096
MAX_CONV_CHANNELS = 512
PATCH_POOLS = (1, 2, 3, 4, 6)
MAX_PRIOR = 20.0
MAX_CAPTORS = 8
MAX_WALL_RAYS = 72
# Cells across the coarse map of net.sight.map_cells (0: no map).
MAP_CELLS = (8, 32)
MAP_CHANNELS = 4


def _wall_rays(net: dict) -> int:
    """The wall rays a network reads after the spec's vector (net.sight)."""
    return int(net.get("sight", {}).get("wall_rays", 0))


def _map_cells(net: dict) -> int:
    """Cells across the coarse map a network reads after the rays
    (net.sight; absent before the map existed: none)."""
    return int(net.get("sight", {}).get("map_cells", 0))


def _sight_len(net: dict) -> int:
    """Numbers the sight appends to each vector: the rays, then the map."""
    cells = _map_cells(net)
    return _wall_rays(net) + MAP_CHANNELS * cells * cells


def _regular(path: Path, listed_by: str) -> None:
    """Refuses a listed file that is missing or not a regular file, from
    its stat alone: a FIFO is never opened (reading one would block)."""
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        raise _refuse(path, f"missing, though {listed_by} lists it") from None
    except OSError as e:
        raise _refuse(path, f"unreadable ({e})") from None
    if not stat.S_ISREG(mode):
        raise _refuse(path, f"not a regular file, though {listed_by} lists it")


def _verify_manifest(folder: Path) -> None:
    """The folder's SHA256SUMS (meta.json included) against its files,
    before meta.json is believed: every checkpoint folder, exported or
    written by training, carries one."""
    manifest = folder / "SHA256SUMS"
    if not manifest.exists():
        raise _refuse(
            manifest,
            f"SHA256SUMS missing: every checkpoint folder carries a manifest (written since 0.2.0); "
            f"re-export it or retrain (a training checkpoint of your own that you trust: `t2e-league seal {folder}`)",
        )
    if not stat.S_ISREG(os.stat(manifest).st_mode):
        raise _refuse(manifest, "not a regular file: a checkpoint's manifest is a file listing `<sha256>  <file>`")
    try:
        text = manifest.read_text()
    except (OSError, UnicodeDecodeError) as e:
        raise _refuse(manifest, f"unreadable ({e})") from None
    listed = set()
    for number, line in enumerate(text.splitlines(), 1):
        if not line.strip():
            continue
        want, sep, name = line.partition("  ")
        if not sep or "/" in name or "\\" in name or name in ("", ".", ".."):
            raise _refuse(manifest, f"line {number} is not `<sha256>  <file>`")
        file = folder / name
        _regular(file, "SHA256SUMS")
        actual = hashlib.sha256(file.read_bytes()).hexdigest()
        if actual != want.strip().lower():
            raise _refuse(file, f"SHA-256 {actual[:12]}... is not the {want.strip()[:12]}... SHA256SUMS lists: the folder changed after it was written")
        listed.add(name)
    if "meta.json" not in listed:
        raise _refuse(manifest, "does not list meta.json")


def _check_player(folder: Path, meta: dict) -> None:
    """An export's player.json names the side meta.json plays."""
    path = folder / "player.json"
    if not path.exists():
        return
    try:
        player = json.loads(path.read_text())
    except (OSError, ValueError, UnicodeDecodeError) as e:
        raise _refuse(path, f"not JSON ({e})") from None
    side = player.get("side") if isinstance(player, dict) else None
    if side != meta["side"]:
        raise _refuse(path, f"side {side!r}, but {folder / 'meta.json'} says {meta['side']!r}: the folder was edited")


def _check_ray_range(path: Path, meta: dict, rays: int) -> None:
    if rays == 0:
        return
    if "wall_ray_range_m" not in meta:
        raise _refuse(
            path,
            f"net.sight.wall_rays = {rays}, but no wall_ray_range_m: the checkpoint was trained when wall rays were "
            f"divided by each map's extent; this version reads them out to a fixed {WALL_RAY_RANGE_M:g} m; retrain it",
        )
    value = meta["wall_ray_range_m"]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or value != WALL_RAY_RANGE_M:
        raise _refuse(path, f"wall_ray_range_m = {value!r}: this version's wall rays read out to {WALL_RAY_RANGE_M:g} m; retrain it")


def _int_field(path: Path, meta: dict, key: str, low: int, high: int, default=None) -> int:
    value = meta.get(key, default)
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise _refuse(path, f"{key} = {value!r}: must be an integer from {low} to {high}")
    return value


def _read_meta(folder: Path) -> dict:
    if not folder.is_dir():
        raise PolicyError(f"{folder}: not a folder (a checkpoint folder holds meta.json and actor.safetensors)")
    path = folder / "meta.json"
    if path.exists() and not path.is_file():
        raise _refuse(path, "not a regular file: not a checkpoint folder")
    if not path.exists() and not (folder / "SHA256SUMS").exists():
        raise _refuse(path, "missing: not a checkpoint folder (export one with `t2e-league export`)")
    _verify_manifest(folder)

    def no_constant(name):
        # NaN and Infinity are not JSON; Python's parser takes them, Rust's does not.
        raise ValueError(f"{name} is not a JSON number")

    try:
        meta = json.loads(path.read_text(), parse_constant=no_constant)
    except (ValueError, UnicodeDecodeError) as e:
        raise _refuse(path, f"not JSON ({e})") from None
    if not isinstance(meta, dict):
        raise _refuse(path, "not a JSON object")
    if meta.get("format") != FORMAT:
        raise _refuse(path, f"format {meta.get('format')!r}; this package reads format {FORMAT}")
    if meta.get("side") not in SIDES:
        raise _refuse(path, f"side {meta.get('side')!r} is neither captors nor target")
    _check_player(folder, meta)
    _int_field(path, meta, "num_captors", 1, MAX_CAPTORS)
    net = meta.get("net", {})
    if not isinstance(net, dict):
        raise _refuse(path, "net is not an object")
    where = f"{path} (net)"
    _int_field(Path(where), net, "hidden", 8, MAX_HIDDEN, 64)
    if net.get("patch_pool", 2) not in PATCH_POOLS:
        raise _refuse(path, f"net.patch_pool = {net.get('patch_pool')!r}: must be one of {PATCH_POOLS}")
    _int_field(Path(where), net, "patch_pool", 1, PATCH, 2)
    channels = net.get("conv_channels", [8, 16])
    if (
        not isinstance(channels, list)
        or len(channels) != 2
        or not all(isinstance(c, int) and not isinstance(c, bool) and 1 <= c <= MAX_CONV_CHANNELS for c in channels)
    ):
        raise _refuse(path, f"net.conv_channels = {channels!r}: must be two integers from 1 to {MAX_CONV_CHANNELS}")
    if net.get("vector_input", "layer_norm") not in VECTOR_INPUTS:
        raise _refuse(path, f"net.vector_input {net.get('vector_input')!r} is not one of {VECTOR_INPUTS}")
    if PATCH % int(net.get("patch_pool", 2)) != 0:
        raise _refuse(path, f"net.patch_pool {net.get('patch_pool')} does not divide {PATCH}")
    if PATCH // int(net.get("patch_pool", 2)) < 7:
        raise _refuse(path, f"net.patch_pool {net.get('patch_pool')}: the pooled patch is too small for the actor's two convolutions")
    sight = net.get("sight", {"wall_rays": 0})
    if not isinstance(sight, dict) or set(sight) - {"wall_rays", "map_cells"}:
        raise _refuse(path, f"net.sight = {sight!r}: must be an object with wall_rays and map_cells")
    rays = sight.get("wall_rays", 0)
    if isinstance(rays, bool) or not isinstance(rays, int) or not (rays == 0 or 4 <= rays <= MAX_WALL_RAYS):
        raise _refuse(path, f"net.sight.wall_rays = {rays!r}: must be 0 or an integer from 4 to {MAX_WALL_RAYS}")
    _check_ray_range(path, meta, rays)
    cells = sight.get("map_cells", 0)
    low, high = MAP_CELLS
    if isinstance(cells, bool) or not isinstance(cells, int) or not (cells == 0 or low <= cells <= high):
        raise _refuse(path, f"net.sight.map_cells = {cells!r}: must be 0 or an integer from {low} to {high}")
    prior = net.get("heuristic_prior", 0.0)
    if isinstance(prior, bool) or not isinstance(prior, (int, float)) or not math.isfinite(prior) or not 0 <= prior <= MAX_PRIOR:
        raise _refuse(path, f"net.heuristic_prior = {prior!r}: must be a number in [0, {MAX_PRIOR}]")
    if "prior_teacher" in net:
        # Its prior leans on a planner this actor does not run: without it
        # the prior would fall on the rule-based target's move.
        raise _refuse(
            path,
            f"net.prior_teacher = {net['prior_teacher']!r}: the network leans on that planner's move, which the PyTorch actor does not compute; "
            "play it by name from Rust (ckpt:PATH, e.g. t2e.vector_env(target='ckpt:PATH')), which builds the planner",
        )
    files = meta.get("files", {})
    if not isinstance(files, dict):
        raise _refuse(path, "files is not an object")
    for name, digest in files.items():
        if not isinstance(name, str) or "/" in name or name in ("", ".", ".."):
            raise _refuse(path, f"files names {name!r}, not a file of the folder")
        file = folder / name
        _regular(file, "meta.json")
        actual = hashlib.sha256(file.read_bytes()).hexdigest()
        if actual != digest:
            raise _refuse(file, f"SHA-256 {actual[:12]}... is not the {str(digest)[:12]}... meta.json records: the file changed")
    if "actor.safetensors" not in files:
        raise _refuse(path, "lists no actor.safetensors")
    return meta


def _vector_features(v, agents: int, kind: str, sight: int = 0):
    """The network's first layer's input from vectors [B, 5 + 5N + sight]
    (`VectorInput` in the Rust nn module; the sight's numbers pass as
    they are)."""
    import torch

    if kind == "layer_norm":
        return v
    per = v.shape[-1] // agents
    n = (per - sight - 5) // 5
    rays = [a * per + 5 + 5 * n + k for a in range(agents) for k in range(sight)]
    if kind == "scaled":
        parts_lin, parts_ang = [], []
        for a in range(agents):
            b = a * per
            idx = [b, b + 1, b + 2, b + 3] + [b + 5 + k for k in range(2 * n)] + [b + 5 + 2 * n + k for k in range(2 * n)]
            idx += [b + 5 + 5 * n + k for k in range(sight)]
            scale = [1.0, 1.0, 1 / POSITION_SCALE, 1 / POSITION_SCALE] + [1.0] * (2 * n) + [1 / POSITION_SCALE] * (2 * n)
            scale += [1.0] * sight
            parts_lin.append(v[..., idx] * torch.tensor(scale, dtype=v.dtype))
            parts_ang.append(v[..., [b + 4] + [b + 5 + 4 * n + k for k in range(n)]])
        lin, ang = torch.cat(parts_lin, -1), torch.cat(parts_ang, -1)
        return torch.cat([lin, ang.sin(), ang.cos()], -1)
    # egocentric
    own = [[a * per + k for a in range(agents)] for k in range(5)]
    vx, vy, px, py, heading = (v[..., i] for i in own)
    cos, sin = heading.cos(), heading.sin()

    def turn(x, y, c, s):
        return x * c + y * s, y * c - x * s

    own_forward, own_left = turn(vx, vy, cos, sin)

    def other(k, j):
        return [5 + 2 * j, 5 + 2 * j + 1, 5 + 2 * n + 2 * j, 5 + 2 * n + 2 * j + 1, 5 + 4 * n + j][k]

    grid = tuple(v.shape[:-1]) + (agents, n)
    ovx, ovy, ox, oy, oh = (
        v[..., [a * per + other(k, j) for a in range(agents) for j in range(n)]].reshape(grid) for k in range(5)
    )
    c, s = cos.unsqueeze(-1), sin.unsqueeze(-1)
    off_f, off_l = turn(ox, oy, c, s)
    dist = (off_f * off_f + off_l * off_l).sqrt()
    reach = dist.clamp_min(MIN_DISTANCE)
    vel_f, vel_l = turn(ovx, ovy, c, s)

    def flat(t):
        return t.flatten(-2, -1)

    return torch.cat(
        [
            own_forward, own_left, px / POSITION_SCALE, py / POSITION_SCALE, sin, cos,
            flat(off_f / POSITION_SCALE), flat(off_l / POSITION_SCALE), flat(dist / POSITION_SCALE),
            flat(off_f / reach), flat(off_l / reach), flat(vel_f), flat(vel_l), flat(oh.sin()), flat(oh.cos()),
            v[..., rays],
        ],
        -1,
    )


def _build_actor(net: dict, vector_len: int):
    import torch
    from torch import nn

    hidden = int(net.get("hidden", 64))
    c1, c2 = (int(c) for c in net.get("conv_channels", (8, 16)))
    side = PATCH // int(net.get("patch_pool", 2))
    side = ((side - 3) // 2 + 1 - 3) // 2 + 1
    kind = net.get("vector_input", "layer_norm")
    sight = _sight_len(net)
    per, n = vector_len, (vector_len - sight - 5) // 5
    width = {"layer_norm": vector_len, "scaled": per + 1 + n, "egocentric": 6 + 9 * n + sight}[kind]

    class Encoder(nn.Module):
        def __init__(self):
            super().__init__()
            self.conv1 = nn.Conv2d(1, c1, 3, stride=2)
            self.conv2 = nn.Conv2d(c1, c2, 3, stride=2)
            self.patch_fc = nn.Linear(c2 * side * side, hidden)
            if kind != "scaled":
                self.vector_norm = nn.LayerNorm(width)
            self.vector_fc = nn.Linear(width, hidden)
            self.merge_fc = nn.Linear(2 * hidden, hidden)

        def forward(self, patches, vectors):
            x = torch.relu(self.conv2(torch.relu(self.conv1(patches.float()))))
            x = torch.relu(self.patch_fc(x.flatten(1)))
            v = _vector_features(vectors, 1, kind, sight)
            if kind != "scaled":
                v = self.vector_norm(v)
            v = torch.relu(self.vector_fc(v))
            return torch.relu(self.merge_fc(torch.cat([x, v], 1)))

    class Actor(nn.Module):
        def __init__(self):
            super().__init__()
            self.encoder = Encoder()
            self.gru = nn.GRU(hidden, hidden)
            self.head = nn.Linear(hidden, ACTIONS)

        def forward(self, patches, vectors, h):
            x = self.encoder(patches, vectors)
            _, h = self.gru(x.unsqueeze(0), h.unsqueeze(0))
            h = h.squeeze(0)
            return self.head(h), h

    return Actor()


def _pool(patches: np.ndarray, pool: int) -> np.ndarray:
    """[B, 48, 48] -> [B, 48 / pool, 48 / pool]: a pooled cell is an
    obstacle where any of its cells is (the Rust `pool_patch`)."""
    b = patches.shape[0]
    s = PATCH // pool
    return patches.reshape(b, s, pool, s, pool).max(axis=(2, 4))


def _latest(checkpoints: Path, side: str) -> Optional[Path]:
    """The newest complete checkpoint of ``side`` in a ``checkpoints``
    folder (``latest_in`` in crates/learners/src/nn/run_dir.rs)."""
    try:
        names = sorted(n for n in os.listdir(checkpoints) if n.startswith(f"{side}-"))
    except OSError:
        return None
    for name in reversed(names):
        if (checkpoints / name / "meta.json").is_file():
            return checkpoints / name
    return None


def _resolve(path: Path, side: Optional[str]) -> Path:
    """The checkpoint folder ``path`` names, as ``ckpt:PATH`` resolves it
    (``resolve_checkpoint`` in crates/learners/src/nn/policy.rs): a
    checkpoint folder, a file in one, or a training run's folder (the
    checkpoint its state.json names, else its newest) or its
    ``checkpoints``. ``side`` None: the one side the run trained."""
    if path.is_file() and (path.parent / "meta.json").is_file():
        return path.parent
    if not path.is_dir():
        raise PolicyError(f"{path}: not a folder (a checkpoint folder holds meta.json and actor.safetensors)")
    if any((path / name).exists() for name in ("meta.json", "SHA256SUMS", "actor.safetensors")):
        return path
    sides = (side,) if side else SIDES
    if any(path.name.startswith(f"{s}-") for s in sides):
        raise _refuse(path / "meta.json", "missing: an incomplete checkpoint (a write that did not finish)")
    found = {}
    state = path / "state.json"
    if state.is_file():
        try:
            named = dict(json.loads(state.read_text()).get("checkpoints", []))
        except (OSError, ValueError, TypeError, AttributeError, UnicodeDecodeError) as e:
            raise _refuse(state, f"not a run's state ({e})") from None
        for s in sides:
            if s in named:
                folder = path / "checkpoints" / str(named[s])
                if not (folder / "meta.json").is_file():
                    raise _refuse(state, f"names the {s} checkpoint {folder}, which is gone")
                found[s] = folder
    else:
        checkpoints = path / "checkpoints" if (path / "checkpoints").is_dir() else path
        for s in sides:
            latest = _latest(checkpoints, s)
            if latest is not None:
                found[s] = latest
    if len(found) == 2:
        raise PolicyError(f"{path}: a run of both sides; say which: load_policy({str(path)!r}, side='captors' or 'target')")
    if not found:
        what = f"no {side} checkpoint" if side else "no checkpoint"
        raise PolicyError(
            f"{path}: no meta.json, and {what} inside (a checkpoint folder holds meta.json and actor.safetensors; "
            "a training run's folder holds checkpoints/)"
        )
    return next(iter(found.values()))


_FORK_HOOKED = False


def _one_thread_after_fork() -> None:
    """A forked child cannot use the thread pools of its parent's torch
    (the OpenMP workers are not copied, and the first parallel kernel
    waits for them forever): the child runs torch on its own thread."""
    global _FORK_HOOKED
    if _FORK_HOOKED or not hasattr(os, "register_at_fork"):
        return

    def child():
        import torch

        torch.set_num_threads(1)
        try:
            torch.set_num_interop_threads(1)
        except RuntimeError:
            pass  # set once already, or after the parent's inter-op work: intra-op is what hangs

    os.register_at_fork(after_in_child=child)
    _FORK_HOOKED = True


class _State:
    """One env's recurrent state and the episode it belongs to."""

    __slots__ = ("hidden", "episode")

    def __init__(self):
        self.hidden = None
        self.episode = None


class TorchPolicy:
    """An exported player's actor in PyTorch, playing its side greedily.

    Call it with the spec observations ``reset``/``step`` returned and the
    env they came from (needed by a target whose checkpoint leans on the
    rule-based target's action); it returns the side's actions. Given the
    env, it checks that the env is one it can play (its K, its sight, its
    side, spec observations) and keeps one recurrent state per env, which
    starts over at each new episode of that env; without it, one state for
    all calls. ``reset()`` starts every state over."""

    def __init__(self, folder, side: Optional[str] = None):
        import torch

        _one_thread_after_fork()
        folder = _resolve(Path(os.path.abspath(folder)), side)
        self.folder = folder
        self.meta = _read_meta(folder)
        self.side = self.meta["side"]
        if side is not None and side != self.side:
            raise _refuse(folder / "meta.json", f"a {self.side} checkpoint, not a {side} one")
        self.num_captors = int(self.meta["num_captors"])
        self.net = self.meta["net"]
        self.wall_rays = _wall_rays(self.net)
        self.map_cells = _map_cells(self.net)
        self.vector_len = 5 + 5 * self.num_captors + _sight_len(self.net)
        self.prior = float(self.net.get("heuristic_prior", 0.0))
        self.actor = _build_actor(self.net, self.vector_len)
        weights = _read_safetensors(folder / "actor.safetensors")
        own = self.actor.state_dict()
        if set(weights) != set(own):
            raise _refuse(folder / "actor.safetensors", f"tensors {sorted(set(weights) ^ set(own))} do not fit the actor meta.json describes")
        for name, t in weights.items():
            if tuple(t.shape) != tuple(own[name].shape):
                raise _refuse(folder / "actor.safetensors", f"tensor {name} has shape {tuple(t.shape)}, the actor {tuple(own[name].shape)}")
        self.actor.load_state_dict(weights)
        self.actor.eval()
        self._torch = torch
        # The state of calls without an env (and of `logits`), then each env's.
        self._free = _State()
        self._states = weakref.WeakKeyDictionary()
        # The rule-based target's action, for a checkpoint that leans on it.
        self._hint = None

    def __repr__(self) -> str:
        return f"load_policy({str(self.folder)!r})"

    def __reduce__(self):
        return (load_policy, (str(self.folder), self.side))

    def agents(self, env) -> list:
        return [a for a in env.possible_agents if (a == "target") == (self.side == "target")]

    def reset(self, env=None):
        """Starts the recurrent state over: ``env``'s, or every one."""
        if env is None:
            self._free = _State()
            self._states.clear()
        else:
            self._states.pop(_unwrap(env), None)

    def _sight(self) -> str:
        if self.map_cells:
            return f"wall_rays={self.wall_rays}, map_cells={self.map_cells}"
        return f"wall_rays={self.wall_rays}"

    def mismatch(self, env) -> Optional[str]:
        """What of ``env`` (a ``t2e.parallel_env``) this player was not
        trained for, K or sight, in a sentence; None when it fits."""
        k = len(env._all_agents) - 1
        theirs = dict(num_captors=k, wall_rays=env.wall_rays, map_cells=env.map_cells)
        ours = dict(num_captors=self.num_captors, wall_rays=self.wall_rays, map_cells=self.map_cells)
        wrong = [f"{name} = {theirs[name]}" for name in ours if ours[name] != theirs[name]]
        if not wrong:
            return None
        shown = [name for name in ours if name == "num_captors" or ours[name] or theirs[name]]
        trained = ", ".join(f"{name} = {ours[name]}" for name in shown)
        want = ", ".join(f"{name}={ours[name]}" for name in shown)
        return (
            f"trained with {trained} (num_captors and net.sight in its meta.json), this env has {', '.join(wrong)}; "
            f"make the env with {want}"
        )

    def _check_env(self, env):
        env = _unwrap(env)
        wrong = self.mismatch(env)
        if wrong:
            raise ValueError(wrong)
        if not self.agents(env):
            raise ValueError(
                f"the env plays the {self.side} itself ({self.side}={env._kwargs.get(self.side)!r}), "
                f"so {self!r}, a {self.side} policy, has no agent there"
            )
        if env.observation != "spec":
            raise ValueError(
                f"pass spec observations: make the env with observation='spec' (this env has observation={env.observation!r})"
            )
        return env

    def _rows(self, observations):
        """The side's agents in ``observations``, and their patches and
        vectors stacked, each shape checked."""
        if not isinstance(observations, dict):
            raise TypeError(
                f"observations = {type(observations).__name__}: pass the dict reset() or step() returned "
                "(agent name -> spec observation)"
            )
        agents = [a for a in observations if (a == "target") == (self.side == "target")]
        if not agents:
            raise ValueError(f"observations hold no {self.side} agent (they name {list(observations)}); {self!r} plays the {self.side}")
        for a in agents:
            o = observations[a]
            if not isinstance(o, dict) or "patch" not in o or "vector" not in o:
                what = f"a dict of {sorted(o)}" if isinstance(o, dict) else f"a {type(o).__name__}"
                raise ValueError(
                    f"observations[{a!r}] is {what}: pass spec observations (dict with patch and vector); "
                    "make the env with observation='spec'"
                )
            if np.shape(o["patch"]) != (PATCH, PATCH):
                raise ValueError(
                    f"observations[{a!r}]['patch'] has shape {np.shape(o['patch'])}: pass spec observations "
                    f"(a {PATCH} x {PATCH} patch); make the env with observation='spec'"
                )
        patches = np.stack([observations[a]["patch"] for a in agents])
        vectors = np.stack([np.asarray(observations[a]["vector"]).reshape(-1) for a in agents])
        if vectors.shape[1] != self.vector_len:
            raise ValueError(
                f"observations: vectors of {vectors.shape[1]} numbers; {self!r} was trained with "
                f"{self.num_captors} captors and {self._sight()} (net.sight in meta.json): "
                f"{self.vector_len} numbers; make the env with num_captors={self.num_captors}, {self._sight()}"
            )
        return agents, patches, vectors

    def _step(self, state: _State, patches: np.ndarray, vectors: np.ndarray):
        torch = self._torch
        pooled = _pool(np.asarray(patches, dtype=np.uint8), int(self.net.get("patch_pool", 2)))
        p = torch.from_numpy(np.ascontiguousarray(pooled)).unsqueeze(1)
        v = torch.from_numpy(np.ascontiguousarray(vectors, dtype=np.float32))
        if state.hidden is None or state.hidden.shape[0] != v.shape[0]:
            state.hidden = torch.zeros(v.shape[0], self.actor.gru.hidden_size)
        with torch.no_grad():
            logits, state.hidden = self.actor(p, v, state.hidden)
        return logits

    def logits(self, patches: np.ndarray, vectors: np.ndarray):
        """Logits [B, 5] of one step for rows of observations (patches
        [B, 48, 48] uint8, vectors [B, 5 + 5 K + sight] float32), advancing the
        recurrent state of calls without an env."""
        patches, vectors = np.asarray(patches), np.asarray(vectors)
        if vectors.ndim != 2 or vectors.shape[1] != self.vector_len:
            raise ValueError(
                f"vectors of shape {vectors.shape}: {self!r} reads [B, {self.vector_len}] "
                f"({self.vector_len} numbers a row: 5 + 5 x {self.num_captors} captors"
                + (f" + {_sight_len(self.net)} of sight" if _sight_len(self.net) else "")
                + ")"
            )
        if patches.shape != (len(vectors), PATCH, PATCH):
            raise ValueError(f"patches of shape {patches.shape}: {self!r} reads [B, {PATCH}, {PATCH}], B = {len(vectors)} as the vectors")
        return self._step(self._free, patches, vectors)

    def __call__(self, observations: dict, env=None) -> Dict[str, int]:
        if env is not None:
            env = self._check_env(env)
        return self._play(observations, env)

    def _play(self, observations: dict, env) -> Dict[str, int]:
        """The actions for ``observations`` of ``env`` (checked, or the env
        this policy plays inside), which may be None."""
        torch = self._torch
        agents, patches, vectors = self._rows(observations)
        if env is None:
            state = self._free
        else:
            state = self._states.get(env)
            if state is None:
                state = self._states[env] = _State()
            episode = (env._env.seed, env._env.map_name)
            if env._env.steps == 0 or episode != state.episode:
                state.hidden = None
                state.episode = episode
        logits = self._step(state, patches, vectors)
        if self.prior > 0 and self.side == "target":
            if env is None:
                raise ValueError(f"{self.folder / 'meta.json'}: this target leans on the rule-based target's action; pass the env")
            if self._hint is None:
                from ._core import Policy

                self._hint = Policy("heuristic", "target")
            hint = int(self._hint.act(env._env)[0])
            logits = logits + self.prior * torch.nn.functional.one_hot(torch.tensor([hint]), ACTIONS).float()
        return {a: int(i) for a, i in zip(agents, logits.argmax(1).tolist())}


def _unwrap(env):
    """The ``t2e.parallel_env`` under ``env`` (``t2e.env()``'s AEC
    wrappers included), or a TypeError naming what was given. Known by
    the native env it holds, so that this module, which the parallel env
    imports, imports nothing back."""
    from ._core import Env

    inner = getattr(env, "unwrapped", env)
    if not isinstance(getattr(inner, "_env", None), Env):
        raise TypeError(
            f"env = {type(env).__name__}: a loaded policy plays a t2e.parallel_env or t2e.env; "
            "for arrays (t2e.vector_env), call policy.logits(patches, vectors)"
        )
    return inner


def load_policy(folder, side: Optional[str] = None) -> TorchPolicy:
    """The actor of a checkpoint folder in PyTorch; refuses a corrupted or
    mismatched folder with the file and the reason (``PolicyError``).
    ``folder`` may be a training run's folder: the checkpoint of ``side``
    its state.json names (``side`` may be left out when the run trained
    one side), as ``ckpt:`` reads it."""
    if not isinstance(folder, (str, os.PathLike)):
        raise TypeError(f"folder = {folder!r}: the path of a checkpoint folder (a str or a Path)")
    if not str(folder):
        raise ValueError("folder = '': the path of a checkpoint folder, not an empty string")
    if side is not None and side not in SIDES:
        raise ValueError(f"side = {side!r}: must be 'captors', 'target' or None (the side a run folder's checkpoint plays)")
    try:
        return TorchPolicy(folder, side)
    except PolicyError:
        raise
    except (KeyError, AttributeError, TypeError, ValueError, ZeroDivisionError, RuntimeError, OSError) as e:
        # Whatever slipped past the checks above still names the folder.
        raise PolicyError(f"{folder}: cannot be played ({type(e).__name__}: {e})") from e
