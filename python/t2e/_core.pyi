"""Type stubs of the Rust extension `t2e._core`."""

from typing import List, Optional, Tuple

import numpy as np
import numpy.typing as npt

ACTIONS: int

class Env:
    """One T2E world: K captors (first) and a target (last)."""

    def __init__(
        self,
        maps: str,
        num_captors: int = 3,
        speed_ratio: float = 1.0,
        protocol: str = "held-out",
        episode_length: int = 500,
        render: bool = False,
        wall_rays: int = 0,
        map_cells: int = 0,
    ) -> None: ...
    @property
    def agent_names(self) -> List[str]: ...
    @property
    def vector_len(self) -> int: ...
    @property
    def wall_rays(self) -> int: ...
    @property
    def map_cells(self) -> int: ...
    @property
    def patch_side(self) -> int: ...
    @property
    def episode_length(self) -> int: ...
    @property
    def steps(self) -> int: ...
    @property
    def map_name(self) -> str: ...
    @property
    def map_names(self) -> List[str]: ...
    @property
    def map_index(self) -> int: ...
    def __reduce__(self) -> Tuple[type, tuple]: ...
    def state(self) -> npt.NDArray[np.float32]: ...
    def reset(self, seed: int) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.uint8]]: ...
    def step(
        self, actions: npt.NDArray[np.int64]
    ) -> Tuple[
        npt.NDArray[np.float32],
        npt.NDArray[np.uint8],
        npt.NDArray[np.float32],
        bool,
        bool,
        bool,
    ]: ...
    def asz_area(self) -> float: ...
    def render(self) -> npt.NDArray[np.uint8]: ...
    @property
    def seed(self) -> int: ...
    @property
    def poses(self) -> List[Tuple[float, float, float]]: ...

class Policy:
    """A controller that plays one side ("captors" or "target") from the
    env's state: heuristic, greedy, greedy:K, random or still."""

    def __init__(self, name: str, side: str) -> None: ...
    @property
    def name(self) -> str: ...
    def act(self, env: Env) -> npt.NDArray[np.int64]: ...

class VectorEnv:
    """n worlds stepped together in Rust, with auto-reset."""

    def __init__(
        self,
        num_envs: int,
        maps: str,
        num_captors: int = 3,
        speed_ratio: float = 1.0,
        protocol: str = "held-out",
        episode_length: int = 500,
        seed: Optional[int] = None,
        captors: Optional[str] = None,
        target: Optional[str] = None,
        wall_rays: int = 0,
        map_cells: int = 0,
    ) -> None: ...
    @property
    def seed(self) -> int: ...
    def __reduce__(self) -> Tuple[type, tuple]: ...
    @property
    def num_envs(self) -> int: ...
    @property
    def num_agents(self) -> int: ...
    @property
    def vector_len(self) -> int: ...
    @property
    def wall_rays(self) -> int: ...
    @property
    def map_cells(self) -> int: ...
    def reset(self) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.uint8]]: ...
    def step(
        self, actions: npt.NDArray[np.int64]
    ) -> Tuple[
        npt.NDArray[np.float32],
        npt.NDArray[np.uint8],
        npt.NDArray[np.float32],
        npt.NDArray[np.bool_],
        npt.NDArray[np.bool_],
    ]: ...

def asz_area(
    env: Env,
    captors: List[Tuple[float, float]],
    target: Tuple[float, float],
    target_speed: float = 1.0,
) -> float: ...

def shaped_observations(
    vectors: npt.NDArray[np.float32],
    patches: npt.NDArray[np.uint8],
    pool: int,
    flat: bool,
    wall_rays: int = 0,
    map_cells: int = 0,
) -> Tuple[npt.NDArray[np.float32], Optional[npt.NDArray[np.uint8]]]: ...
