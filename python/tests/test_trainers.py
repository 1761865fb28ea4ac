"""The env with the trainers people use, as they are: SuperSuit's vector
envs (in-process and in worker processes), Stable-Baselines3's PPO through
them (an MLP on the flat observation, its CNN policies on the image),
TorchRL's PettingZooWrapper with its spec check and the global state,
and PettingZoo's own render test, unedited (its API, max_cycles and state
tests are in test_portable.py and test_pettingzoo.py). RLlib and
BenchMARL are in test_marl_trainers.py.

They are the optional `trainers` group (python/pyproject.toml), which
scripts/setup.sh installs at pinned versions; the test command sets
T2E_TRAINERS_REQUIRED=1 so that a missing library fails rather than skips."""

import importlib
import os
import warnings

import numpy as np
import pytest

import t2e


def need(module: str):
    if os.environ.get("T2E_TRAINERS_REQUIRED") == "1":
        return importlib.import_module(module)
    return pytest.importorskip(module)


def captors_env(**kwargs):
    """The captors' side alone, the rule-based target inside, as one flat
    vector per captor: what SuperSuit and an MLP policy take."""
    return t2e.parallel_env(maps="shipped", target="heuristic", observation="flat", **kwargs)


@pytest.mark.parametrize("num_cpus", [0, 2])
def test_supersuit_vector_envs_step_and_report_captures(num_cpus):
    ss = need("supersuit")
    env = captors_env(episode_length=60)
    venv = ss.concat_vec_envs_v1(ss.pettingzoo_env_to_vec_env_v1(env), 4, num_cpus=num_cpus, base_class="stable_baselines3")
    try:
        observations = venv.reset()
        assert observations.shape == (12,) + env.observation_space("captor_0").shape
        assert observations.dtype == np.float32
        rng = np.random.default_rng(0)
        ends, captures = 0, 0
        for _ in range(130):
            observations, rewards, dones, infos = venv.step(rng.integers(5, size=12))
            assert observations.shape[0] == 12 and rewards.shape == (12,)
            for done, info in zip(dones, infos):
                assert isinstance(info["captured"], bool)
                assert all(isinstance(v, (bool, int, float, np.ndarray)) for v in info.values())
                ends += bool(done)
                captures += bool(done) and info["captured"]
        # 130 steps of 60-step episodes: every world ended twice, 3 agents each.
        assert ends == 2 * 12
        assert captures <= ends
    finally:
        venv.close()


def test_supersuit_keeps_a_capture_through_its_reset():
    ss = need("supersuit")
    # The target alone is the agent and stands still; the rule-based
    # captors trap it in some episodes and not in others.
    def make():
        return t2e.parallel_env(maps="shipped", captors="heuristic", observation="flat", episode_length=150)

    venv = ss.concat_vec_envs_v1(ss.pettingzoo_env_to_vec_env_v1(make()), 2, num_cpus=0)
    venv.reset(seed=3)
    through_supersuit = []
    while len(through_supersuit) < 8:
        _, _, terminations, truncations, infos = venv.step(np.full(2, 3))
        if terminations[0] or truncations[0]:
            assert infos[0]["captured"] == bool(terminations[0])
            through_supersuit.append(infos[0]["captured"])
    # SuperSuit's first world plays seed 3, then that env's own sequence.
    plain = make()
    plain.reset(seed=3)
    direct = []
    while len(direct) < 8:
        *_, terminations, _, infos = plain.step({"target": 3})
        if not plain.agents:
            direct.append(infos["target"]["captured"])
            plain.reset()
    assert through_supersuit == direct
    assert any(direct) and not all(direct)


def test_stable_baselines3_ppo_learns_from_it():
    ss = need("supersuit")
    sb3 = need("stable_baselines3")
    torch = need("torch")
    torch.set_num_threads(1)
    venv = ss.concat_vec_envs_v1(
        ss.pettingzoo_env_to_vec_env_v1(captors_env(episode_length=100)), 2, num_cpus=0, base_class="stable_baselines3"
    )
    try:
        # Not PPO(seed=...): SB3 then calls venv.seed(), which SuperSuit's
        # vector env lacks (a SuperSuit limit, whatever the env).
        sb3.common.utils.set_random_seed(0)
        model = sb3.PPO("MlpPolicy", venv, n_steps=64, batch_size=128, n_epochs=2, device="cpu", verbose=0)
        before = [p.detach().clone() for p in model.policy.parameters()]
        model.learn(total_timesteps=3 * 6 * 64)
        after = list(model.policy.parameters())
        assert model.num_timesteps >= 3 * 6 * 64
        assert any(not torch.equal(a, b) for a, b in zip(before, after))
        assert all(torch.isfinite(p).all() for p in after)
        actions, _ = model.predict(venv.reset(), deterministic=True)
        assert actions.shape == (6,) and set(actions.tolist()) <= set(range(t2e.ACTIONS))
    finally:
        venv.close()


def test_stable_baselines3_cnn_policies_learn_from_the_image():
    ss = need("supersuit")
    sb3 = need("stable_baselines3")
    torch = need("torch")
    from stable_baselines3.common.preprocessing import is_image_space
    from stable_baselines3.common.torch_layers import NatureCNN
    from stable_baselines3.common.vec_env import VecTransposeImage

    torch.set_num_threads(1)
    env = t2e.parallel_env(maps="shipped", target="heuristic", observation="image", episode_length=100)
    assert is_image_space(env.observation_space("captor_0")["patch"])
    # The patch alone, for CnnPolicy: one SuperSuit wrapper.
    patch_only = ss.observation_lambda_v0(env, lambda observation, _: observation["patch"], lambda space: space["patch"])

    def vec(parallel):
        return ss.concat_vec_envs_v1(ss.pettingzoo_env_to_vec_env_v1(parallel), 2, num_cpus=0, base_class="stable_baselines3")

    # CnnPolicy takes a Box only; for the Dict, SB3's CNN policy is
    # MultiInputPolicy, whose CombinedExtractor runs NatureCNN on "patch".
    with pytest.raises(ValueError, match="MultiInputPolicy"):
        sb3.PPO("CnnPolicy", vec(env), device="cpu")
    for policy, parallel in (("MultiInputPolicy", env), ("CnnPolicy", patch_only)):
        venv = vec(parallel)
        try:
            sb3.common.utils.set_random_seed(0)
            model = sb3.PPO(policy, venv, n_steps=64, batch_size=128, n_epochs=2, device="cpu", verbose=0)
            # Taken as an image: channel-last moved first, NatureCNN on it.
            assert isinstance(model.get_env(), VecTransposeImage)
            assert any(isinstance(m, NatureCNN) for m in model.policy.modules())
            before = [p.detach().clone() for p in model.policy.parameters()]
            model.learn(total_timesteps=3 * 6 * 64)
            after = list(model.policy.parameters())
            assert model.num_timesteps >= 3 * 6 * 64
            assert any(not torch.equal(a, b) for a, b in zip(before, after))
            assert all(torch.isfinite(p).all() for p in after)
        finally:
            venv.close()


@pytest.mark.parametrize("kwargs", [{}, {"target": "heuristic", "observation": "egocentric"}])
def test_torchrl_wrapper_passes_its_spec_check_with_the_state(kwargs):
    need("torchrl")
    from torchrl.envs.libs.pettingzoo import PettingZooWrapper
    from torchrl.envs.utils import check_env_specs

    with warnings.catch_warnings():
        # TorchRL names the PettingZoo version it was tested with.
        warnings.simplefilter("ignore", UserWarning)
        env = PettingZooWrapper(t2e.parallel_env(maps="shipped", episode_length=40, **kwargs), return_state=True)
    check_env_specs(env, seed=0)
    rollout = env.rollout(90, break_when_any_done=False)
    assert rollout["next", "state"].shape == (90, 5 * 4 + 1)
    assert set(env.group_map) == ({"captor"} if kwargs else {"captor", "target"})
    # Infos arrive as numbers; `captured` is the episode's termination.
    captured = rollout["next", "captor", "info", "captured"].bool()
    assert torch_equal(captured, rollout["next", "captor", "terminated"].squeeze(-1))
    assert rollout["next", "captor", "truncated"].sum() > 0


def torch_equal(a, b) -> bool:
    return bool((a == b).all())


def test_pettingzoo_render_test_in_both_modes():
    from pettingzoo.test import render_test

    matplotlib = need("matplotlib")
    # No display here: "human" draws into matplotlib's non-interactive backend.
    matplotlib.use("Agg")
    render_test(lambda render_mode=None: t2e.env(maps="shipped", render_mode=render_mode))
