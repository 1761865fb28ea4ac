"""The T2E target-trapping benchmark from Python.

``t2e.parallel_env(...)`` is a PettingZoo ``ParallelEnv`` over the Rust
environment of t2e-league: K captor robots try to trap one target robot on
real indoor maps. Observations per agent are a dict of the 48 x 48 obstacle
patch around the robot (uint8, 1 = obstacle) and its vector (float32,
5 + 5 K numbers); actions are integers in 0..5. See docs/guide/python.md.
"""

from ._core import ACTIONS, Env
from .env import T2EParallelEnv, parallel_env

__all__ = ["ACTIONS", "Env", "T2EParallelEnv", "parallel_env"]
