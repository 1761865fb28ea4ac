"""The T2E env for RLlib's multi-agent algorithms (Ray's new API stack),
one policy per side::

    from ray.rllib.algorithms.ppo import PPOConfig
    import t2e.rllib

    env_config = {"target": "heuristic", "observation": "flat", "episode_length": 200}
    config = (PPOConfig().environment(t2e.rllib.register(), env_config=env_config)
              .multi_agent(policies=t2e.rllib.policies(env_config), policy_mapping_fn=t2e.rllib.side))
    algo = config.build_algo()
    for _ in range(100):
        algo.train()

``env_config`` is ``t2e.parallel_env``'s keyword arguments. RLlib's
default encoders take a Box: ``observation="flat"`` (an MLP), not the
Dict of ``spec``, ``egocentric`` or ``image``, for which RLlib builds no
encoder by itself. Needs ``ray[rllib]`` installed; the env does not.
"""

from __future__ import annotations

from typing import Set

from .parallel import parallel_env


def register(name: str = "t2e") -> str:
    """Registers ``name`` with Ray's env registry, made from an env_config
    of ``parallel_env`` arguments through RLlib's ParallelPettingZooEnv;
    returns the name for ``.environment(...)``."""
    from ray.rllib.env.wrappers.pettingzoo_env import ParallelPettingZooEnv
    from ray.tune.registry import register_env

    # EnvContext is a dict that also carries the worker's index: only its items are arguments.
    register_env(name, lambda env_config: ParallelPettingZooEnv(parallel_env(**dict(env_config))))
    return name


def side(agent_id: str, *args, **kwargs) -> str:
    """The policy an agent plays: ``captors`` or ``target`` (RLlib's
    policy_mapping_fn)."""
    return "target" if agent_id == "target" else "captors"


def policies(env_config: dict) -> Set[str]:
    """The sides that learn in an env made from ``env_config``: those
    that no built-in opponent plays."""
    return {s for s in ("captors", "target") if env_config.get(s) is None}
