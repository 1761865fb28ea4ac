"""What ``parallel_env`` hands each agent, by its ``observation`` argument.

- ``spec``: the paper's observation (docs/reference/env.md): the 48 x 48
  obstacle patch, heading up, and the 5 + 5N vector in the world's axes.
- ``egocentric``: what the Rust learners' networks read (``vector_input =
  "egocentric"`` with ``patch_pool``): the vector turned into the robot's
  own frame, 6 + 9N numbers, and the patch max-pooled.
- ``flat``: the egocentric vector followed by the pooled patch as 0/1
  floats, one float32 Box, for off-the-shelf MLP policies.

The egocentric numbers are those of ``nn/egocentric.rs`` (and of
``torch_policy._vector_features``): per robot, its velocity as (forward,
left), its position / 8 m, sine and cosine of its heading; per other robot,
its offset as (forward, left) / 8 m, its distance / 8 m, its bearing as
(cosine, sine), its velocity as (forward, left), sine and cosine of its
heading relative to ours. Numpy only: the env needs no torch.
"""

from __future__ import annotations

import numpy as np
from gymnasium import spaces

KINDS = ("spec", "egocentric", "flat")
PATCH_POOLS = (1, 2, 3, 4, 6)
PATCH = 48
# Half the 16 m map: positions and distances come out within about [-1, 1].
POSITION_SCALE = 8.0
# A bearing is taken at this distance at least; robots never overlap by that much.
MIN_DISTANCE = 1e-3


def check(kind, patch_pool) -> None:
    if kind not in KINDS:
        raise ValueError(f"observation = {kind!r}: must be one of {', '.join(KINDS)}")
    if isinstance(patch_pool, bool) or not isinstance(patch_pool, (int, np.integer)) or patch_pool not in PATCH_POOLS:
        raise ValueError(f"patch_pool = {patch_pool!r}: must be one of {PATCH_POOLS} (it divides the 48-cell patch)")


def egocentric_width(vector_len: int) -> int:
    others = (vector_len - 5) // 5
    return 6 + 9 * others


def space(kind: str, patch_pool: int, vector_len: int) -> spaces.Space:
    if kind == "spec":
        return spaces.Dict(
            {
                "patch": spaces.Box(0, 1, shape=(PATCH, PATCH), dtype=np.uint8),
                "vector": spaces.Box(-np.inf, np.inf, shape=(vector_len,), dtype=np.float32),
            }
        )
    side = PATCH // patch_pool
    width = egocentric_width(vector_len)
    if kind == "egocentric":
        return spaces.Dict(
            {
                "patch": spaces.Box(0, 1, shape=(side, side), dtype=np.uint8),
                "vector": spaces.Box(-np.inf, np.inf, shape=(width,), dtype=np.float32),
            }
        )
    return spaces.Box(-np.inf, np.inf, shape=(width + side * side,), dtype=np.float32)


def pool(patches: np.ndarray, patch_pool: int) -> np.ndarray:
    """[B, 48, 48] -> [B, 48 / pool, 48 / pool]: a pooled cell is an obstacle
    where any of its cells is (the Rust ``pool_patch``)."""
    if patch_pool == 1:
        return patches
    b = patches.shape[0]
    s = PATCH // patch_pool
    return patches.reshape(b, s, patch_pool, s, patch_pool).max(axis=(2, 4))


def egocentric(vectors: np.ndarray) -> np.ndarray:
    """[B, 5 + 5N] spec vectors -> [B, 6 + 9N], each row in its robot's frame."""
    v = np.asarray(vectors, dtype=np.float32)
    n = (v.shape[1] - 5) // 5
    vx, vy, px, py, heading = (v[:, k] for k in range(5))
    cos, sin = np.cos(heading), np.sin(heading)

    # World axes to the robot's (forward, left): forward = (cos, sin), left = (-sin, cos).
    def turn(x, y, c, s):
        return x * c + y * s, y * c - x * s

    own_forward, own_left = turn(vx, vy, cos, sin)
    velocities = v[:, 5 : 5 + 2 * n].reshape(-1, n, 2)
    offsets = v[:, 5 + 2 * n : 5 + 4 * n].reshape(-1, n, 2)
    headings = v[:, 5 + 4 * n : 5 + 5 * n]
    c, s = cos[:, None], sin[:, None]
    off_f, off_l = turn(offsets[..., 0], offsets[..., 1], c, s)
    distance = np.sqrt(off_f * off_f + off_l * off_l)
    reach = np.maximum(distance, MIN_DISTANCE)
    vel_f, vel_l = turn(velocities[..., 0], velocities[..., 1], c, s)
    return np.concatenate(
        [
            np.stack([own_forward, own_left, px / POSITION_SCALE, py / POSITION_SCALE, sin, cos], axis=1),
            off_f / POSITION_SCALE,
            off_l / POSITION_SCALE,
            distance / POSITION_SCALE,
            off_f / reach,
            off_l / reach,
            vel_f,
            vel_l,
            np.sin(headings),
            np.cos(headings),
        ],
        axis=1,
    ).astype(np.float32, copy=False)


def build(kind: str, patch_pool: int, vectors: np.ndarray, patches: np.ndarray):
    """One observation per row of ``vectors`` [A, 5 + 5N] and ``patches``
    [A, 48, 48], as ``kind`` shapes them."""
    if kind == "spec":
        return [{"patch": patches[i], "vector": vectors[i]} for i in range(len(vectors))]
    vector = egocentric(vectors)
    pooled = pool(patches, patch_pool)
    if kind == "egocentric":
        return [{"patch": pooled[i], "vector": vector[i]} for i in range(len(vectors))]
    flat = np.concatenate([vector, pooled.reshape(len(vectors), -1).astype(np.float32)], axis=1)
    return list(flat)
