"""The PettingZoo parallel API over ``t2e._core.Env``."""

from __future__ import annotations

import math
import numbers
import os
from typing import Any, Dict, Optional

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv
from pettingzoo.utils.conversions import parallel_to_aec_wrapper
from pettingzoo.utils.wrappers import OrderEnforcingWrapper

from . import observations as obs
from ._core import ACTIONS, Env, Policy
from .policies import ScriptedPolicy
from .torch_policy import TorchPolicy

# Episode seeds are those of the Rust side: integers in 0..2**64.
_SEED_LIMIT = 2**64


class T2EParallelEnv(ParallelEnv):
    """K captors and one target on the maps ``maps`` names.

    Agents are ``captor_0`` .. ``captor_{K-1}`` and ``target``. Each episode
    ends for all agents at once: ``terminations`` when the captors trap the
    target (the fast capture rule: every probe around the target is
    blocked; docs/reference/env.md), ``truncations`` at
    ``episode_length`` steps (``max_cycles`` is the same number, by
    PettingZoo's name). Infos are numbers only: ``map_index`` (into
    ``map_names``; ``map_name`` is this episode's), ``captured`` (whether
    this env's most recent step trapped the target: after ``reset``, the
    previous episode's last step, False for the first; so wrappers that
    merge reset infos over the last step's, as SuperSuit does, keep it, and
    those that take the info keys from ``reset``, as TorchRL does, find
    it), and ``asz_area`` (m^2) when ``asz_info`` is on.

    Arguments: ``maps`` a map selection (``shipped``, ``generated:N``,
    ``small,medium,large``, a folder, or a comma list); ``num_captors`` K,
    1 to 8; ``speed_ratio`` the target's top speed over the captors'
    (1.0 to 1.4 in the paper); ``protocol`` ``held-out`` (training maps
    that are not the Gibson test set), ``paper`` (the 26 Gibson maps) or
    ``test`` (the Gibson maps, to evaluate); ``episode_length`` steps
    before truncation; ``render_mode`` None, ``rgb_array`` (``render()``
    returns the frame) or ``human`` (``render()`` shows it in a matplotlib
    window and returns None); ``observation`` ``spec`` (the paper's patch
    and vector), ``egocentric`` (the Rust learners' inputs: the vector in
    the robot's frame and the patch max-pooled by ``patch_pool``),
    ``flat`` (those two in one float32 vector, for MLP policies) or
    ``image`` (the spec's vector and the whole patch as a 48 x 48 x 1
    uint8 image, obstacle 255, for CNN policies; t2e/observations.py);
    ``asz_info``
    whether every step computes the exact ASZ (per-robot arrival fields,
    about 3.5 ms a step on the shipped maps;
    off by default); ``captors`` or ``target`` a built-in opponent that
    plays that side inside the env (``heuristic``, ``greedy``,
    ``greedy:K``, ``random``, ``still``, ``ckpt:FOLDER`` for an exported
    player, or a policy from ``t2e.load_policy``), so only the other side's
    agents remain; ``wall_rays`` 0 (the spec's observation) or 4 to 72
    wall distances in the robot's frame across the map, appended to every
    vector (the learners' `net.sight`; not in the paper; a player trained
    with them needs them); ``map_cells`` 0 (no map) or 8 to 32: a coarse
    north-up map of the whole map, ``map_cells`` cells across, in four
    channels (walls' share of the cell, captors in it, the target, this
    robot), 4 * map_cells**2 numbers after the rays (`net.sight` too; a
    player trained with it needs it). Pickling or copying the env makes a new one from the
    same arguments and random state; it starts without an episode.
    ``state()`` is the global state a centralised critic reads.
    """

    metadata = {"name": "t2e_v1", "render_modes": ["rgb_array", "human"], "is_parallelizable": True, "render_fps": 10}

    def __init__(
        self,
        maps: str = "shipped",
        num_captors: int = 3,
        speed_ratio: float = 1.0,
        protocol: str = "held-out",
        episode_length: int = 500,
        render_mode: Optional[str] = None,
        asz_info: bool = False,
        max_cycles: Optional[int] = None,
        captors: Any = None,
        target: Any = None,
        observation: str = "spec",
        patch_pool: int = 4,
        wall_rays: int = 0,
        map_cells: int = 0,
    ):
        if max_cycles is not None:
            _check_range("max_cycles", max_cycles, 1, MAX_EPISODE_LENGTH)
            if episode_length not in (500, max_cycles):
                raise ValueError(
                    f"max_cycles = {max_cycles} and episode_length = {episode_length}: the same number by two names; give one"
                )
            episode_length = max_cycles
        self._kwargs = dict(
            maps=maps,
            num_captors=num_captors,
            speed_ratio=speed_ratio,
            protocol=protocol,
            episode_length=episode_length,
            render_mode=render_mode,
            asz_info=asz_info,
            captors=_picklable(captors),
            target=_picklable(target),
            observation=observation,
            patch_pool=patch_pool,
            wall_rays=wall_rays,
            map_cells=map_cells,
        )
        check_settings(num_captors, speed_ratio, episode_length, wall_rays, map_cells)
        if not isinstance(maps, str):
            raise TypeError(f"maps = {maps!r}: must be a string such as 'shipped', 'generated:20' or 'small,medium,large'")
        if not isinstance(protocol, str):
            raise TypeError(f"protocol = {protocol!r}: must be 'held-out', 'paper' or 'test'")
        if not isinstance(asz_info, (bool, np.bool_)):
            # bool("no") is True: a string here would silently turn it on.
            raise TypeError(f"asz_info = {asz_info!r}: must be True or False")
        if render_mode not in (None, "rgb_array", "human"):
            raise ValueError(f"render_mode = {render_mode!r}: must be None, 'rgb_array' or 'human'")
        obs.check(observation, patch_pool)
        self.observation = observation
        self.patch_pool = int(patch_pool)
        self._window = _Window() if render_mode == "human" else None
        self._env = Env(
            maps,
            int(num_captors),
            float(speed_ratio),
            protocol,
            int(episode_length),
            render_mode is not None,
            int(wall_rays),
            int(map_cells),
        )
        self.wall_rays = int(wall_rays)
        self.map_cells = int(map_cells)
        self.render_mode = render_mode
        self.asz_info = bool(asz_info)
        self.max_cycles = int(episode_length)
        self.map_names = list(self._env.map_names)
        self._all_agents = list(self._env.agent_names)
        self._index = {a: i for i, a in enumerate(self._all_agents)}
        self._opponents = {}
        for name, spec in (("captors", captors), ("target", target)):
            if spec is not None:
                self._opponents[name] = opponent = _opponent(name, spec)
                # A copy loads the very folder this env loaded, wherever it runs.
                self._kwargs[name] = _picklable(opponent) if isinstance(opponent, TorchPolicy) else _picklable(spec)
        for name, opponent in self._opponents.items():
            # A loaded policy reads this env's vectors as they are.
            wrong = opponent.mismatch(self) if isinstance(opponent, TorchPolicy) else None
            if wrong:
                raise ValueError(f"{name} = {opponent!r}: {wrong}")
        if len(self._opponents) == 2:
            raise ValueError("captors and target: both sides played by built-in opponents leaves no agent to act")
        self.possible_agents = [a for a in self._all_agents if _side(a) not in self._opponents]
        # The rows of the env's arrays that are this env's agents.
        self._rows = [self._index[a] for a in self.possible_agents]
        self.agents: list[str] = []
        self._last = None
        self._captured = False
        space = obs.space(observation, self.patch_pool, self._env.vector_len, self.wall_rays, self.map_cells)
        self.observation_spaces = {a: space for a in self.possible_agents}
        self.action_spaces = {a: spaces.Discrete(ACTIONS) for a in self.possible_agents}
        self.state_space = spaces.Box(-np.inf, np.inf, shape=(5 * len(self._all_agents) + 1,), dtype=np.float32)
        self._rng = np.random.default_rng()
        self._started = False

    def __reduce__(self):
        return (_rebuild, (self._kwargs, self._rng.bit_generator.state))

    def state(self) -> np.ndarray:
        """Every robot's x, y (m, world frame), vx, vy (m/s) and heading
        (rad), captors first, then the share of the episode left: what a
        centralised critic reads (``state_space``)."""
        self._need_reset("state")
        return self._env.state()

    @property
    def map_name(self) -> str:
        """The name of this episode's map (``map_names[infos[a]["map_index"]]``)."""
        return self._env.map_name

    def observation_space(self, agent: str) -> spaces.Space:
        if agent not in self.observation_spaces:
            raise ValueError(f"agent = {agent!r}: not one of {self.possible_agents}")
        return self.observation_spaces[agent]

    def action_space(self, agent: str) -> spaces.Space:
        if agent not in self.action_spaces:
            raise ValueError(f"agent = {agent!r}: not one of {self.possible_agents}")
        return self.action_spaces[agent]

    def reset(self, seed: Optional[int] = None, options: Optional[dict] = None):
        """Starts an episode: the one of ``seed`` (same seed, same episode),
        or the next of this env's own sequence when ``seed`` is None.
        ``options`` is accepted as PettingZoo passes it, and read for
        nothing: an episode is its seed."""
        if seed is None:
            episode = int(self._rng.integers(_SEED_LIMIT, dtype=np.uint64))
        else:
            _check_int("seed", seed)
            if seed < 0:
                raise ValueError(f"seed = {seed}: must be a non-negative integer")
            if seed >= _SEED_LIMIT:
                raise ValueError(f"seed = {seed}: must be below 2**64")
            episode = int(seed)
            self._rng = np.random.default_rng(episode)
        vectors, patches = self._env.reset(episode)
        self._started = True
        self.agents = list(self.possible_agents)
        for opponent in self._opponents.values():
            if isinstance(opponent, TorchPolicy):
                # This env's state alone: the same policy may play other envs.
                opponent.reset(self)
            elif hasattr(opponent, "reset") and not isinstance(opponent, Policy):
                opponent.reset()
        observations = self._observations(vectors, patches)
        return observations, self._infos()

    def step(self, actions: Dict[str, Any]):
        if not self.agents:
            raise RuntimeError("step() after the episode ended (or before reset()): call reset() first")
        if not isinstance(actions, dict):
            raise TypeError(f"actions = {actions!r}: must be a dict from agent name to action")
        missing = [a for a in self.agents if a not in actions]
        unknown = [a for a in actions if a not in self.agents]
        if missing or unknown:
            raise ValueError(
                f"actions: must name every live agent once ({', '.join(self.agents)}); "
                + (f"missing {missing}" if missing else f"unknown {unknown}")
            )
        index = self._index
        chosen = np.empty(len(self._all_agents), dtype=np.int64)
        for agent in self.agents:
            chosen[index[agent]] = _action(agent, actions[agent])
        for side, opponent in self._opponents.items():
            for agent, action in self._opponent_actions(side, opponent).items():
                chosen[index[agent]] = action
        vectors, patches, rewards, terminated, truncated, captured = self._env.step(chosen)
        observations = self._observations(vectors, patches)
        agents = self.agents
        reward = {a: float(rewards[index[a]]) for a in agents}
        terminations = {a: bool(terminated) for a in agents}
        truncations = {a: bool(truncated) for a in agents}
        self._captured = bool(captured)
        infos = self._infos()
        if terminated or truncated:
            self.agents = []
        return observations, reward, terminations, truncations, infos

    def render(self, mode: Optional[str] = None):
        """The current state as an RGB frame [H, W, 3] uint8 (``render_mode
        = "rgb_array"``): the map, the ASZ shaded, the robots and their
        trails, as ``t2e-league render`` draws them. With ``"human"`` the
        frame is shown in a window and None returned; None without a render
        mode. ``mode``, where given (RLlib passes ``render_mode``), must be
        the env's ``render_mode``: it is chosen when the env is made."""
        if mode is not None and mode != self.render_mode:
            raise ValueError(
                f"render(mode={mode!r}): this env renders {self.render_mode!r}, chosen when it was made; "
                f"make it with render_mode={mode!r}"
            )
        if self.render_mode is None:
            return None
        self._need_reset("render")
        frame = self._env.render()
        if self._window is not None:
            self._window.show(frame, self.metadata["render_fps"])
            return None
        return frame

    def asz_area(self) -> float:
        """|ASZ| of the current state in m^2."""
        self._need_reset("asz_area")
        return self._env.asz_area()

    def _need_reset(self, what: str) -> None:
        if not self._started:
            raise RuntimeError(f"{what}() before reset(): there is no state yet; call reset() first")

    def close(self):
        if self._window is not None:
            self._window.close()

    def _observations(self, vectors: np.ndarray, patches: np.ndarray):
        # A loaded policy playing a side reads the spec's observations,
        # whatever this env hands out; controllers read the env itself.
        if any(not isinstance(o, Policy) for o in self._opponents.values()):
            self._last = {a: {"patch": patches[i], "vector": vectors[i]} for i, a in enumerate(self._all_agents)}
        mine = self._rows
        shaped = obs.build(
            self.observation, self.patch_pool, vectors[mine], patches[mine], self.wall_rays, self.map_cells
        )
        return dict(zip(self.possible_agents, shaped))

    def _opponent_actions(self, side: str, opponent) -> Dict[str, int]:
        mine = [a for a in self._all_agents if _side(a) == side]
        if isinstance(opponent, Policy):
            return dict(zip(mine, opponent.act(self._env).tolist()))
        # A loaded policy reads its side's spec observations, as it would
        # outside, whatever this env hands its own agents.
        seen = {a: self._last[a] for a in mine}
        return opponent._play(seen, self) if isinstance(opponent, TorchPolicy) else opponent(seen, self)

    def _infos(self):
        info = {"map_index": self._env.map_index, "captured": self._captured}
        if self.asz_info:
            info["asz_area"] = self._env.asz_area()
        return {a: dict(info) for a in self.possible_agents}



class _Window:
    """A matplotlib window for ``render_mode="human"``, opened on the first
    frame. Where no display is available, matplotlib's non-interactive
    backend draws into nothing, and the frame is simply not seen."""

    def __init__(self):
        try:
            import matplotlib  # noqa: F401
        except ImportError:
            raise ImportError("render_mode = 'human' shows frames with matplotlib: pip install matplotlib") from None
        self._figure = None
        self._image = None

    def show(self, frame: np.ndarray, fps: int) -> None:
        import matplotlib.pyplot as plt

        if self._figure is None:
            self._figure = plt.figure("t2e")
            self._image = plt.imshow(frame)
            plt.axis("off")
        else:
            self._image.set_data(frame)
        plt.pause(1.0 / fps)

    def close(self) -> None:
        if self._figure is not None:
            import matplotlib.pyplot as plt

            plt.close(self._figure)
            self._figure = None


def _side(agent: str) -> str:
    return "target" if agent == "target" else "captors"


def _opponent(side: str, spec: Any):
    """A built-in opponent for ``side``: a controller by name, ``ckpt:FOLDER``
    (an exported player, or a training run's folder), a ``ScriptedPolicy``,
    or a policy from ``t2e.load_policy``."""
    if isinstance(spec, str):
        if spec.startswith("ckpt:"):
            from .torch_policy import PolicyError, load_policy

            try:
                return load_policy(spec[len("ckpt:") :], side)
            except PolicyError as e:
                raise PolicyError(f"{side} = {spec!r}: {e}") from None
        return Policy(spec, side)
    if isinstance(spec, (ScriptedPolicy, TorchPolicy)):
        if spec.side != side:
            raise ValueError(
                f"{side} = {spec!r}: a policy of the {spec.side} side; give it as {spec.side}=, "
                f"or a {side} policy as {side}="
            )
        # The controller it wraps, played in Rust from the env's state.
        return Policy(spec.name, side) if isinstance(spec, ScriptedPolicy) else spec
    if callable(spec) and getattr(spec, "side", None) in ("captors", "target"):
        # A policy of one's own, called as a loaded one is: (observations, env).
        if spec.side != side:
            raise ValueError(f"{side} = {spec!r}: a policy of the {spec.side} side")
        return spec
    raise TypeError(
        f"{side} = {spec!r}: a controller name (heuristic, greedy, greedy:K, random, still), "
        "'ckpt:FOLDER', a t2e.ScriptedPolicy (t2e.rule_based_target() and the like), or a policy from t2e.load_policy"
    )


def _picklable(spec: Any) -> Any:
    """A loaded policy is pickled as the folder it came from, a scripted one
    as its controller's name, a ``ckpt:`` path made absolute (a copy may be
    made in another working folder)."""
    if isinstance(spec, TorchPolicy):
        return f"ckpt:{spec.folder}"
    if isinstance(spec, ScriptedPolicy):
        return spec.name
    if isinstance(spec, str) and spec.startswith("ckpt:"):
        return "ckpt:" + os.path.abspath(spec[len("ckpt:") :])
    return spec


def _rebuild(kwargs: dict, rng_state: dict) -> "T2EParallelEnv":
    env = T2EParallelEnv(**kwargs)
    env._rng.bit_generator.state = rng_state
    return env


def _check_int(name: str, value: Any) -> None:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} = {value!r}: must be an integer")


MAX_CAPTORS = 8
MAX_EPISODE_LENGTH = 1_000_000
WALL_RAYS = (4, 72)
MAP_CELLS = (8, 32)


def _check_range(name: str, value: Any, low: int, high: int, zero: str = "") -> None:
    """An integer from ``low`` to ``high`` (or 0, where ``zero`` says what 0
    means), checked here so that a huge one is named, not an OverflowError
    of the Rust side's."""
    _check_int(name, value)
    if not (low <= value <= high or (zero and value == 0)):
        allowed = f"0 ({zero}) or between {low} and {high}" if zero else f"between {low} and {high}"
        raise ValueError(f"{name} = {value}: must be {allowed}")


def check_settings(num_captors, speed_ratio, episode_length, wall_rays, map_cells) -> None:
    """The settings ``parallel_env`` and ``vector_env`` share, each refused
    by name."""
    _check_range("num_captors", num_captors, 1, MAX_CAPTORS)
    if isinstance(speed_ratio, bool) or not isinstance(speed_ratio, numbers.Real):
        raise TypeError(f"speed_ratio = {speed_ratio!r}: must be a number (v_e / v_p)")
    try:
        ratio = float(speed_ratio)
    except OverflowError:
        ratio = math.inf
    if not (math.isfinite(ratio) and 0 < ratio <= 10):
        raise ValueError(f"speed_ratio = {speed_ratio!r}: must be a number in (0, 10]: v_e / v_p, 1.0 to 1.4 in the paper")
    _check_range("episode_length", episode_length, 1, MAX_EPISODE_LENGTH)
    _check_range("wall_rays", wall_rays, *WALL_RAYS, zero="the spec's observation")
    _check_range("map_cells", map_cells, *MAP_CELLS, zero="no map")


def _action(agent: str, value: Any) -> int:
    """An action as an int in 0..ACTIONS, or a ValueError naming the agent."""
    if isinstance(value, np.ndarray):
        if value.shape not in ((), (1,)):
            raise ValueError(f"actions[{agent!r}]: an array of shape {value.shape}; one action is a scalar")
        value = value.reshape(()).item()
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ValueError(f"actions[{agent!r}] = {value!r}: an action is an integer from 0 to {ACTIONS - 1}")
    if not 0 <= value < ACTIONS:
        raise ValueError(f"actions[{agent!r}] = {value}: an action is an integer from 0 to {ACTIONS - 1}")
    return int(value)


# The class itself, so `parallel_env` has the class's explicit signature
# and docstring (PettingZoo's tools call `mod.parallel_env(**kwargs)`).
parallel_env = T2EParallelEnv


def env(**kwargs):
    """The same env with PettingZoo's AEC API (agents act in turn, the
    step resolved once all have); arguments as ``parallel_env``. Pickled
    or copied, it is a new env without an episode, as the parallel env
    is: ``reset`` it."""
    return _aec(parallel_env(**kwargs))


class _AEC(OrderEnforcingWrapper):
    """PettingZoo's AEC wrappers over a parallel env, copied as a new env."""

    # A copy of the wrappers' dicts would keep the turn order and the live
    # agents of an episode that the copied parallel env does not have.
    def __reduce__(self):
        return (_aec, (self.unwrapped,))


def _aec(parallel: T2EParallelEnv) -> _AEC:
    return _AEC(parallel_to_aec_wrapper(parallel))
