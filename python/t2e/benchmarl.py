"""The T2E env as a BenchMARL task, so BenchMARL's algorithms (MAPPO,
IPPO, QMIX, ...) train on it as on its own PettingZoo tasks::

    from benchmarl.algorithms import MappoConfig
    from benchmarl.experiment import Experiment
    from benchmarl.models import MlpConfig
    from t2e.benchmarl import T2ETask, experiment_config

    experiment = Experiment(task=T2ETask.CAPTORS.get_task({"episode_length": 200}),
                            algorithm_config=MappoConfig.get_from_yaml(), model_config=MlpConfig.get_from_yaml(),
                            critic_model_config=MlpConfig.get_from_yaml(), seed=0,
                            config=experiment_config(max_n_iters=100, loggers=["csv"]))
    experiment.run()

A task's config is ``t2e.parallel_env``'s keyword arguments. The tasks
default to ``observation="flat"``, which BenchMARL's MLP reads: its MLP
refuses the spec's 48 x 48 patch (a 2-D input). ``observation="image"``
is for its CNN (``CnnConfig``), as the actor's model; the centralised
critic then reads ``state``, a plain vector, and takes ``MlpConfig``.

The env reaches BenchMARL through TorchRL's ``PettingZooWrapper``, with
the global state (``env.state()``) for centralised critics and one
TorchRL group per side (``captor``, ``target``). Needs ``benchmarl``
installed; the env itself does not.
"""

from __future__ import annotations

import copy
from typing import Callable, Dict, List, Optional

from benchmarl.environments.common import Task, TaskClass
from benchmarl.experiment import ExperimentConfig
from torchrl.data import Composite
from torchrl.envs import EnvBase
from torchrl.envs.libs.pettingzoo import PettingZooWrapper

from .parallel import parallel_env

# What each task plays inside the env; the rest of its config is the user's.
_SIDES = {
    "CAPTORS": {"target": "heuristic"},
    "TARGET": {"captors": "heuristic"},
    "BOTH": {},
}
_DEFAULTS = {"maps": "shipped", "observation": "flat", "episode_length": 500}


class T2EClass(TaskClass):
    """BenchMARL's handle on one T2E task (``T2ETask.X.get_task(config)``)."""

    def get_env_fun(self, num_envs: int, continuous_actions: bool, seed: Optional[int], device) -> Callable[[], EnvBase]:
        config = copy.deepcopy(self.config)
        # BenchMARL batches a non-vectorised env itself (SerialEnv / ParallelEnv of num_envs).
        return lambda: PettingZooWrapper(
            parallel_env(**config), return_state=True, categorical_actions=True, device=device, seed=seed
        )

    def supports_continuous_actions(self) -> bool:
        return False

    def supports_discrete_actions(self) -> bool:
        return True

    def has_render(self, env: EnvBase) -> bool:
        return self.config.get("render_mode") == "rgb_array"

    def max_steps(self, env: EnvBase) -> int:
        return int(self.config.get("max_cycles") or self.config.get("episode_length", 500))

    def group_map(self, env: EnvBase) -> Dict[str, List[str]]:
        return env.group_map

    def _only(self, env: EnvBase, key: str) -> Composite:
        spec = env.observation_spec.clone()
        for group in self.group_map(env):
            for name in list(spec[group].keys()):
                if name != key:
                    del spec[group][name]
        if "state" in spec.keys():
            del spec["state"]
        return spec

    def observation_spec(self, env: EnvBase) -> Composite:
        return self._only(env, "observation")

    def info_spec(self, env: EnvBase) -> Optional[Composite]:
        return self._only(env, "info")

    def state_spec(self, env: EnvBase) -> Optional[Composite]:
        return Composite({"state": env.observation_spec["state"].clone()})

    def action_mask_spec(self, env: EnvBase) -> Optional[Composite]:
        return None

    def action_spec(self, env: EnvBase) -> Composite:
        return env.full_action_spec

    @staticmethod
    def env_name() -> str:
        return "t2e"


class T2ETask(Task):
    """``CAPTORS``: the captors learn against the rule-based target inside
    the env; ``TARGET``: the target against the expert captors; ``BOTH``:
    two groups, both sides learning."""

    CAPTORS = None
    TARGET = None
    BOTH = None

    @staticmethod
    def associated_class():
        return T2EClass

    def get_task(self, config: Optional[dict] = None) -> T2EClass:
        # No yaml file ships for these tasks: the defaults are here.
        return T2EClass(name=self.name, config={**_DEFAULTS, **_SIDES[self.name], **(config or {})})

    def get_from_yaml(self, path: Optional[str] = None) -> T2EClass:
        if path is None:
            return self.get_task()
        return super().get_from_yaml(path)


def experiment_config(**fields) -> ExperimentConfig:
    """BenchMARL's default ExperimentConfig with ``fields`` set. Its
    defaults log to wandb, which BenchMARL does not install: give
    ``loggers`` (``[]``, ``["csv"]``, ...) unless wandb is there."""
    config = ExperimentConfig.get_from_yaml()
    for name, value in fields.items():
        if not hasattr(config, name):
            raise ValueError(f"{name} = {value!r}: not a field of BenchMARL's ExperimentConfig")
        setattr(config, name, value)
    return config
