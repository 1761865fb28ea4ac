"""The rule-based robots and the ASZ-greedy planner as policies."""

from __future__ import annotations

from typing import Dict

from ._core import Policy


class ScriptedPolicy:
    """Plays one side of a ``T2EParallelEnv`` from its state, as the Rust
    evaluation does: ``heuristic`` (the expert captors, or the rule-based
    target), ``greedy`` / ``greedy:K`` (the ASZ-greedy planner), ``random``
    or ``still``. Call it with the env; it returns the side's actions."""

    def __init__(self, name: str = "heuristic", side: str = "target"):
        self._policy = Policy(name, side)
        self.side = side

    def __repr__(self) -> str:
        return f"ScriptedPolicy({self.name!r}, {self.side!r})"

    @property
    def name(self) -> str:
        return self._policy.name

    def __call__(self, env) -> Dict[str, int]:
        core = getattr(env, "_env", None)
        if core is None:
            raise TypeError(
                f"env = {type(env).__name__}: a ScriptedPolicy plays a t2e.parallel_env; "
                "for t2e.vector_env, name the controller there (vector_env(..., target='heuristic'))"
            )
        actions = self._policy.act(core).tolist()
        agents = [a for a in env.possible_agents if (a == "target") == (self.side == "target")]
        return dict(zip(agents, actions))


def rule_based_target() -> ScriptedPolicy:
    """The paper's rule-based target."""
    return ScriptedPolicy("heuristic", "target")


def expert_captors() -> ScriptedPolicy:
    """The paper's expert captors."""
    return ScriptedPolicy("heuristic", "captors")


def greedy_captors(coarsening: int = 1) -> ScriptedPolicy:
    """The ASZ-greedy captors: each picks the move that leaves the smallest
    ASZ (marching on cells ``coarsening`` times the map's, 1 = exact)."""
    import numbers

    if isinstance(coarsening, bool) or not isinstance(coarsening, numbers.Integral):
        raise TypeError(f"coarsening = {coarsening!r}: must be an integer from 1 to 8")
    return ScriptedPolicy("greedy" if coarsening == 1 else f"greedy:{int(coarsening)}", "captors")
