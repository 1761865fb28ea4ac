"""What ``parallel_env`` hands each agent, by its ``observation`` argument.

- ``spec``: the paper's observation (docs/reference/env.md): the 48 x 48
  obstacle patch, heading up, and the 5 + 5N vector in the world's axes.
- ``egocentric``: what the Rust learners' networks read (``vector_input =
  "egocentric"`` with ``patch_pool``): the vector turned into the robot's
  own frame, 6 + 9N numbers, and the patch max-pooled.
- with ``wall_rays``, each vector ends in that many wall distances in the
  robot's frame (divided by a fixed 16 m, capped at 1), in every kind; with
  ``map_cells``, then in a coarse north-up map of the whole map,
  ``map_cells`` x ``map_cells`` cells in four channels (walls, captors,
  target, self), 4 * map_cells**2 numbers, row by row.
- ``flat``: the egocentric vector followed by the pooled patch as 0/1
  floats, one float32 Box, for off-the-shelf MLP policies.
- ``image``: the spec's vector beside the whole patch as a one-channel
  image, 48 x 48 x 1 uint8, obstacle 255 and free 0: image bounds with
  the channel last are what Stable-Baselines3's ``is_image_space`` and
  the CNN encoders of RLlib and BenchMARL take without a wrapper.
  ``patch_pool`` does not apply (a CNN does its own pooling).

The arrays are made in Rust (``t2e._core.shaped_observations``, over
crates/core/src/env/features.rs), with the numbers of the learners'
networks: per robot, its velocity as (forward, left), its position / 8 m,
sine and cosine of its heading; per other robot, its offset as (forward,
left) / 8 m, its distance / 8 m, its bearing as (cosine, sine), its
velocity as (forward, left), sine and cosine of its heading relative to
ours. The env needs no torch.
"""

from __future__ import annotations

import numpy as np
from gymnasium import spaces

from ._core import shaped_observations

KINDS = ("spec", "egocentric", "flat", "image")
PATCH_POOLS = (1, 2, 3, 4, 6)
PATCH = 48


def check(kind, patch_pool) -> None:
    if kind not in KINDS:
        raise ValueError(f"observation = {kind!r}: must be one of {', '.join(KINDS)}")
    if isinstance(patch_pool, bool) or not isinstance(patch_pool, (int, np.integer)) or patch_pool not in PATCH_POOLS:
        raise ValueError(f"patch_pool = {patch_pool!r}: must be one of {PATCH_POOLS} (it divides the 48-cell patch)")


def sight_len(wall_rays: int = 0, map_cells: int = 0) -> int:
    """Numbers the sight appends to each vector: the rays, then the map's
    four channels of ``map_cells`` x ``map_cells``."""
    return wall_rays + 4 * map_cells * map_cells


def egocentric_width(vector_len: int, wall_rays: int = 0, map_cells: int = 0) -> int:
    sight = sight_len(wall_rays, map_cells)
    others = (vector_len - sight - 5) // 5
    return 6 + 9 * others + sight


def space(kind: str, patch_pool: int, vector_len: int, wall_rays: int = 0, map_cells: int = 0) -> spaces.Space:
    if kind == "spec":
        return spaces.Dict(
            {
                "patch": spaces.Box(0, 1, shape=(PATCH, PATCH), dtype=np.uint8),
                "vector": spaces.Box(-np.inf, np.inf, shape=(vector_len,), dtype=np.float32),
            }
        )
    if kind == "image":
        return spaces.Dict(
            {
                "patch": spaces.Box(0, 255, shape=(PATCH, PATCH, 1), dtype=np.uint8),
                "vector": spaces.Box(-np.inf, np.inf, shape=(vector_len,), dtype=np.float32),
            }
        )
    side = PATCH // patch_pool
    width = egocentric_width(vector_len, wall_rays, map_cells)
    if kind == "egocentric":
        return spaces.Dict(
            {
                "patch": spaces.Box(0, 1, shape=(side, side), dtype=np.uint8),
                "vector": spaces.Box(-np.inf, np.inf, shape=(width,), dtype=np.float32),
            }
        )
    return spaces.Box(-np.inf, np.inf, shape=(width + side * side,), dtype=np.float32)


def egocentric(vectors: np.ndarray) -> np.ndarray:
    """[B, 5 + 5N] spec vectors -> [B, 6 + 9N], each row in its robot's frame."""
    vectors = np.asarray(vectors, dtype=np.float32)
    return shaped_observations(vectors, np.zeros((len(vectors), PATCH, PATCH), np.uint8), 1, False)[0]


def build(
    kind: str, patch_pool: int, vectors: np.ndarray, patches: np.ndarray, wall_rays: int = 0, map_cells: int = 0
):
    """One observation per row of ``vectors`` [A, 5 + 5N + wall_rays +
    4 map_cells^2] and ``patches`` [A, 48, 48], as ``kind`` shapes them
    (the wall rays and the map, if any, follow the egocentric vector as
    they are)."""
    if kind == "spec":
        return [{"patch": patches[i], "vector": vectors[i]} for i in range(len(vectors))]
    if kind == "image":
        # One multiply over the whole [A, 48, 48] block; 0/1 * 255 fits uint8.
        images = np.multiply(patches, np.uint8(255))[..., None]
        return [{"patch": images[i], "vector": vectors[i]} for i in range(len(vectors))]
    shaped, pooled = shaped_observations(vectors, patches, patch_pool, kind == "flat", wall_rays, map_cells)
    if kind == "egocentric":
        return [{"patch": pooled[i], "vector": shaped[i]} for i in range(len(vectors))]
    return list(shaped)
