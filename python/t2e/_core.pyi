"""Type stubs of the Rust extension `t2e._core`."""

from typing import List, Tuple

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
    ) -> None: ...
    @property
    def agent_names(self) -> List[str]: ...
    @property
    def vector_len(self) -> int: ...
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
