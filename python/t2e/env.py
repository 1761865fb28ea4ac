"""The PettingZoo parallel API over ``t2e._core.Env``."""

from __future__ import annotations

import numbers
from typing import Any, Dict, Optional

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from ._core import ACTIONS, Env

# Episode seeds are those of the Rust side: integers in 0..2**64.
_SEED_LIMIT = 2**64


class T2EParallelEnv(ParallelEnv):
    """K captors and one target on the maps ``maps`` names.

    Agents are ``captor_0`` .. ``captor_{K-1}`` and ``target``. Each episode
    ends for all agents at once: ``terminations`` when the captors trap the
    target (the fast capture rule: every probe around the target is
    blocked; docs/reference/env.md), ``truncations`` at
    ``episode_length`` steps. ``infos`` carry ``captured``, ``asz_area``
    (m^2, computed when ``asz_info`` is on) and ``map``.
    """

    metadata = {"name": "t2e_v0", "render_modes": ["rgb_array"], "is_parallelizable": True, "render_fps": 10}

    def __init__(
        self,
        maps: str = "shipped",
        num_captors: int = 3,
        speed_ratio: float = 1.0,
        protocol: str = "held-out",
        episode_length: int = 500,
        render_mode: Optional[str] = None,
        asz_info: bool = True,
    ):
        _check_int("num_captors", num_captors)
        _check_int("episode_length", episode_length)
        if not isinstance(speed_ratio, numbers.Real) or isinstance(speed_ratio, bool):
            raise TypeError(f"speed_ratio = {speed_ratio!r}: must be a number (v_e / v_p)")
        if not isinstance(maps, str):
            raise TypeError(f"maps = {maps!r}: must be a string such as 'shipped', 'generated:20' or 'small,medium,large'")
        if not isinstance(protocol, str):
            raise TypeError(f"protocol = {protocol!r}: must be 'held-out', 'paper' or 'test'")
        if not isinstance(asz_info, (bool, np.bool_)):
            # bool("no") is True: a string here would silently turn it on.
            raise TypeError(f"asz_info = {asz_info!r}: must be True or False")
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode = {render_mode!r}: must be None or 'rgb_array'")
        self._env = Env(
            maps, int(num_captors), float(speed_ratio), protocol, int(episode_length), render_mode == "rgb_array"
        )
        self.render_mode = render_mode
        self.asz_info = bool(asz_info)
        self.possible_agents = list(self._env.agent_names)
        self.agents: list[str] = []
        side = self._env.patch_side
        observation = spaces.Dict(
            {
                "patch": spaces.Box(0, 1, shape=(side, side), dtype=np.uint8),
                "vector": spaces.Box(-np.inf, np.inf, shape=(self._env.vector_len,), dtype=np.float32),
            }
        )
        self.observation_spaces = {a: observation for a in self.possible_agents}
        self.action_spaces = {a: spaces.Discrete(ACTIONS) for a in self.possible_agents}
        self._rng = np.random.default_rng()

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
        self.agents = list(self.possible_agents)
        observations = self._observations(vectors, patches)
        return observations, self._infos(captured=False)

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
        chosen = np.empty(len(self.agents), dtype=np.int64)
        for i, agent in enumerate(self.agents):
            chosen[i] = _action(agent, actions[agent])
        vectors, patches, rewards, terminated, truncated, captured = self._env.step(chosen)
        observations = self._observations(vectors, patches)
        agents = self.agents
        reward = {a: float(rewards[i]) for i, a in enumerate(agents)}
        terminations = {a: bool(terminated) for a in agents}
        truncations = {a: bool(truncated) for a in agents}
        infos = self._infos(captured=bool(captured))
        if terminated or truncated:
            self.agents = []
        return observations, reward, terminations, truncations, infos

    def render(self):
        """The current state as an RGB frame [H, W, 3] uint8 (``render_mode
        = "rgb_array"``): the map, the ASZ shaded, the robots and their
        trails, as ``t2e-league render`` draws them. None without a render
        mode."""
        if self.render_mode is None:
            return None
        return self._env.render()

    def asz_area(self) -> float:
        """|ASZ| of the current state in m^2."""
        return self._env.asz_area()

    def close(self):
        pass

    def _observations(self, vectors: np.ndarray, patches: np.ndarray):
        return {a: {"patch": patches[i], "vector": vectors[i]} for i, a in enumerate(self.possible_agents)}

    def _infos(self, captured: bool):
        info = {"captured": captured, "map": self._env.map_name}
        if self.asz_info:
            info["asz_area"] = self._env.asz_area()
        return {a: dict(info) for a in self.possible_agents}


def _check_int(name: str, value: Any) -> None:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} = {value!r}: must be an integer")


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


def parallel_env(**kwargs) -> T2EParallelEnv:
    """A T2E env with PettingZoo's parallel API; see ``T2EParallelEnv``."""
    return T2EParallelEnv(**kwargs)
