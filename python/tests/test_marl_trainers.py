"""The env with the multi-agent trainers, each through the recipe
docs/guide/python.md gives: RLlib's PPO with one policy per side
(t2e.rllib), and BenchMARL's MAPPO on the task t2e ships
(t2e.benchmarl), with an MLP on the flat observation and a CNN on the
image. Each trains two iterations on small batches, on the CPU.

Like test_trainers.py, they are the `trainers` group at the versions
scripts/setup.sh pins, and fail rather than skip under
T2E_TRAINERS_REQUIRED=1."""

import importlib
import os
import shutil
import tempfile
import warnings

import pytest

import t2e


def need(module: str):
    if os.environ.get("T2E_TRAINERS_REQUIRED") == "1":
        return importlib.import_module(module)
    return pytest.importorskip(module)


def test_rllib_ppo_trains_a_policy_per_side(monkeypatch):
    ray = need("ray")
    need("ray.rllib")
    torch = need("torch")
    import t2e.rllib
    from ray.rllib.algorithms.ppo import PPOConfig

    torch.set_num_threads(1)
    # Nothing leaves the machine; the cluster's files go in a folder of
    # this test's own, short enough for the sockets Ray makes in it
    # (pytest's tmp_path is past the 107 bytes of a Unix socket's path).
    monkeypatch.setenv("RAY_USAGE_STATS_ENABLED", "0")
    folder = tempfile.mkdtemp(prefix="t2e-ray-")
    ray.init(
        num_cpus=2, include_dashboard=False, log_to_driver=False, object_store_memory=200 * 2**20, _temp_dir=folder
    )
    try:
        # The recipe, as the guide gives it; only the sizes are the test's.
        env_config = {"maps": "shipped", "observation": "flat", "episode_length": 100}
        config = (
            PPOConfig()
            .environment(t2e.rllib.register(), env_config=env_config)
            .multi_agent(policies=t2e.rllib.policies(env_config), policy_mapping_fn=t2e.rllib.side)
            .env_runners(num_env_runners=0)
            .training(train_batch_size_per_learner=400, minibatch_size=100, num_epochs=2)
            .debugging(seed=0)
        )
        algo = config.build_algo()
        before = {m: [p.detach().clone() for p in algo.get_module(m).parameters()] for m in ("captors", "target")}
        for _ in range(2):
            result = algo.train()
        assert result["training_iteration"] == 2
        assert result["env_runners"]["num_env_steps_sampled_lifetime"] >= 800
        assert {"captors", "target"} <= set(result["learners"])
        for module, old in before.items():
            new = list(algo.get_module(module).parameters())
            assert any(not torch.equal(a, b) for a, b in zip(old, new)), module
            assert all(torch.isfinite(p).all() for p in new)
    finally:
        # Sampling and learning run in this process (no runner actors): the cluster goes with ray.shutdown.
        ray.shutdown()
        shutil.rmtree(folder, ignore_errors=True)


def benchmarl_run(task, model_config, tmp_path):
    from benchmarl.algorithms import MappoConfig
    from benchmarl.experiment import Experiment
    from benchmarl.models import MlpConfig
    from t2e.benchmarl import experiment_config

    config = experiment_config(
        max_n_iters=2, on_policy_collected_frames_per_batch=400, on_policy_n_envs_per_worker=2,
        on_policy_n_minibatch_iters=2, on_policy_minibatch_size=200,
        loggers=[], evaluation=False, render=False, create_json=False, save_folder=str(tmp_path),
    )
    with warnings.catch_warnings():
        # TorchRL names the PettingZoo version it was tested with.
        warnings.simplefilter("ignore", UserWarning)
        experiment = Experiment(
            task=task, algorithm_config=MappoConfig.get_from_yaml(), model_config=model_config,
            critic_model_config=MlpConfig.get_from_yaml(), seed=0, config=config,
        )
        before = {g: [p.detach().clone() for p in experiment.group_policies[g].parameters()] for g in experiment.group_map}
        experiment.run()
    for group, old in before.items():
        new = list(experiment.group_policies[group].parameters())
        assert any(not torch_equal(a, b) for a, b in zip(old, new)), group
        assert all(bool(p.isfinite().all()) for p in new), group
    return experiment


def torch_equal(a, b) -> bool:
    return bool((a == b).all())


@pytest.mark.parametrize("name", ["CAPTORS", "BOTH"])
def test_benchmarl_mappo_trains_on_the_shipped_task(name, tmp_path):
    need("benchmarl")
    torch = need("torch")
    from benchmarl.models import MlpConfig
    from t2e.benchmarl import T2ETask

    torch.set_num_threads(1)
    task = getattr(T2ETask, name).get_task({"episode_length": 100})
    experiment = benchmarl_run(task, MlpConfig.get_from_yaml(), tmp_path)
    assert experiment.n_iters_performed == 2 and experiment.total_frames == 800
    assert set(experiment.group_map) == ({"captor"} if name == "CAPTORS" else {"captor", "target"})


def test_benchmarl_cnn_reads_the_image(tmp_path):
    need("benchmarl")
    torch = need("torch")
    from benchmarl.models import CnnConfig
    from t2e.benchmarl import T2ETask

    torch.set_num_threads(1)
    cnn = CnnConfig.get_from_yaml()
    # BenchMARL's default CNN keeps all 48 x 48 cells (stride 1): strided
    # layers keep two iterations within seconds on two cores.
    cnn.cnn_num_cells, cnn.cnn_kernel_sizes, cnn.cnn_strides = [16, 16], [8, 4], [4, 2]
    task = T2ETask.CAPTORS.get_task({"episode_length": 100, "observation": "image"})
    experiment = benchmarl_run(task, cnn, tmp_path)
    assert experiment.n_iters_performed == 2
    spec = experiment.observation_spec["captor", "observation", "patch"]
    assert spec.shape[-3:] == (48, 48, 1) and spec.dtype == torch.uint8
