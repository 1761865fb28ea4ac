"""The T2E target-trapping benchmark from Python.

``t2e.parallel_env(...)`` is a PettingZoo ``ParallelEnv`` over the Rust
environment of t2e-league: K captor robots try to trap one target robot on
real indoor maps. Observations per agent are a dict of the 48 x 48 obstacle
patch around the robot (uint8, 1 = obstacle) and its vector (float32,
5 + 5 K numbers); actions are integers in 0..5. ``t2e.vector_env(n, ...)``
steps n worlds at once in Rust, with numpy arrays in and out. See
docs/guide/python.md.
"""

from ._core import ACTIONS, Env, Policy, VectorEnv, asz_area
from .parallel import T2EParallelEnv, env, parallel_env
from . import torch_policy  # noqa: F401  (torch is imported when a policy loads)
from .policies import ScriptedPolicy, expert_captors, greedy_captors, rule_based_target


def load_policy(folder):
    """An exported player (``t2e-league export``, or a training run's
    checkpoint folder) as a PyTorch actor playing its side; see
    ``t2e.torch_policy``. Needs torch installed."""
    from .torch_policy import load_policy as load

    return load(folder)


def vector_env(
    num_envs: int,
    maps: str = "shipped",
    num_captors: int = 3,
    speed_ratio: float = 1.0,
    protocol: str = "held-out",
    episode_length: int = 500,
    seed: int = None,
    captors: str = None,
    target: str = None,
    wall_rays: int = 0,
    map_cells: int = 0,
) -> VectorEnv:
    """``num_envs`` worlds stepped together in Rust, in parallel and without
    the GIL. ``reset()`` returns (vectors [n, N, 5 + 5 K] float32, patches
    [n, N, 48, 48] uint8); ``step(actions [n, N] int64)`` returns (vectors,
    patches, rewards [n, N], terminated [n], truncated [n]). A world whose
    episode ends starts the next at once (its seed drawn from ``seed``, the
    world and the episode), so the arrays always hold live episodes.
    ``captors`` or ``target`` names a controller that plays that side in
    Rust (heuristic, greedy, greedy:K, random, still); the actions given
    for it are then ignored. ``seed=None`` draws a seed from the operating
    system, as ``parallel_env().reset(seed=None)`` does; the env's ``seed``
    attribute says which, so the run can be repeated. ``wall_rays``
    appends that many wall distances in each robot's frame to its vector
    (0: the spec's observation; see ``parallel_env``), and ``map_cells``
    (0, or 8 to 32) a coarse map of the whole map after them, 4 *
    map_cells**2 numbers (walls, captors, target, self)."""
    import numbers

    for name, value in (
        ("num_envs", num_envs),
        ("num_captors", num_captors),
        ("episode_length", episode_length),
        ("wall_rays", wall_rays),
        ("map_cells", map_cells),
    ):
        if isinstance(value, bool) or not isinstance(value, numbers.Integral):
            raise TypeError(f"{name} = {value!r}: must be an integer")
    if isinstance(speed_ratio, bool) or not isinstance(speed_ratio, numbers.Real):
        raise TypeError(f"speed_ratio = {speed_ratio!r}: must be a number (v_e / v_p)")
    if seed is None:
        import secrets

        seed = secrets.randbits(64)
    elif isinstance(seed, bool) or not isinstance(seed, numbers.Integral):
        raise TypeError(f"seed = {seed!r}: must be an integer in 0..2**64 or None")
    return VectorEnv(
        num_envs, maps, num_captors, speed_ratio, protocol, episode_length, seed, captors, target, wall_rays, map_cells
    )


__all__ = [
    "ACTIONS",
    "Env",
    "Policy",
    "ScriptedPolicy",
    "T2EParallelEnv",
    "VectorEnv",
    "asz_area",
    "env",
    "expert_captors",
    "greedy_captors",
    "load_policy",
    "parallel_env",
    "rule_based_target",
    "vector_env",
]
