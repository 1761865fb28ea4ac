"""The T2E target-trapping benchmark from Python.

``t2e.parallel_env(...)`` is a PettingZoo ``ParallelEnv`` over the Rust
environment of t2e-league: K captor robots try to trap one target robot on
real indoor maps. Observations per agent are a dict of the 48 x 48 obstacle
patch around the robot (uint8, 1 = obstacle) and its vector (float32,
5 + 5 K numbers); actions are integers from 0 to 4. ``t2e.vector_env(n, ...)``
steps n worlds at once in Rust, with numpy arrays in and out. See
docs/guide/python.md.
"""

from ._core import ACTIONS, Env, Policy, VectorEnv, asz_area
from .parallel import T2EParallelEnv, check_settings, env, parallel_env
from . import torch_policy  # noqa: F401  (torch is imported when a policy loads)
from .policies import ScriptedPolicy, expert_captors, greedy_captors, rule_based_target


def load_policy(folder, side: str = None):
    """An exported player (``t2e-league export``, a training run's
    checkpoint folder, or the run's folder: the checkpoint of ``side`` its
    state.json names, as ``ckpt:`` reads it) as a PyTorch actor playing
    its side; see ``t2e.torch_policy``. Needs torch installed."""
    from .torch_policy import load_policy as load

    return load(folder, side)


def _scripted_name(side: str, policy: ScriptedPolicy) -> str:
    if policy.side != side:
        raise ValueError(f"{side} = {policy!r}: a policy of the {policy.side} side")
    return policy.name


# Worlds one vector env holds (python/src/lib.rs).
MAX_VECTOR_ENVS = 65_536


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

    if isinstance(num_envs, bool) or not isinstance(num_envs, numbers.Integral):
        raise TypeError(f"num_envs = {num_envs!r}: must be an integer")
    if not 1 <= num_envs <= MAX_VECTOR_ENVS:
        raise ValueError(f"num_envs = {num_envs}: must be between 1 and {MAX_VECTOR_ENVS}")
    check_settings(num_captors, speed_ratio, episode_length, wall_rays, map_cells)
    # A scripted policy is its controller, which Rust plays by name.
    if isinstance(captors, ScriptedPolicy):
        captors = _scripted_name("captors", captors)
    if isinstance(target, ScriptedPolicy):
        target = _scripted_name("target", target)
    for name, value in (("captors", captors), ("target", target)):
        if isinstance(value, str) and value.startswith("ckpt:"):
            raise ValueError(
                f"{name} = {value!r}: vector_env plays only the controllers Rust steps without Python "
                f"(heuristic, greedy, greedy:K, random, still); for a checkpoint, use parallel_env({name}={value!r})"
            )
    for name, value in (("maps", maps), ("protocol", protocol), ("captors", captors), ("target", target)):
        if value is not None and not isinstance(value, str):
            raise TypeError(f"{name} = {value!r}: must be a string" + (" (a controller name; vector_env plays controllers in Rust)" if name in ("captors", "target") else ""))
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
