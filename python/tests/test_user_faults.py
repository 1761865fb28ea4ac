"""What a user gets wrong with loaded policies, opponents, copies and
forks, and what the package says then: each mistake is refused naming the
input and the fix, or made to work. Each test failed before its fix."""

import copy
import os
import pickle
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import t2e

torch = pytest.importorskip("torch")

from test_load_policy import write_checkpoint  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
STORED = ROOT / "tests" / "fixtures" / "stored"
CAPTORS = STORED / "export-captors"  # K = 2
TARGET = STORED / "export-target"  # K = 2


def test_a_policy_is_checked_against_the_env_it_plays(tmp_path):
    # K = 3 and K = 1 with 10 rays have vectors of the same 20 numbers.
    k3 = t2e.load_policy(write_checkpoint(tmp_path / "k3", "captors", 3))
    env = t2e.parallel_env(maps="shipped", num_captors=1, wall_rays=10)
    observations, _ = env.reset(seed=0)
    with pytest.raises(ValueError, match="trained with num_captors = 3, wall_rays = 0 .*this env has num_captors = 1, wall_rays = 10; make the env with num_captors=3, wall_rays=0"):
        k3(observations, env)
    # K = 2 and K = 1 with 5 rays: 15 numbers each.
    policy = t2e.load_policy(CAPTORS)
    env = t2e.parallel_env(maps="shipped", num_captors=1, wall_rays=5)
    observations, _ = env.reset(seed=0)
    with pytest.raises(ValueError, match="this env has num_captors = 1, wall_rays = 5"):
        policy(observations, env)
    for kind in ("egocentric", "flat"):
        env = t2e.parallel_env(maps="shipped", num_captors=2, observation=kind)
        observations, _ = env.reset(seed=0)
        with pytest.raises(ValueError, match=rf"make the env with observation='spec' \(this env has observation='{kind}'\)"):
            policy(observations, env)
    # The captors are played inside this env: the policy has no agent there.
    env = t2e.parallel_env(maps="shipped", num_captors=2, captors="heuristic")
    observations, _ = env.reset(seed=0)
    with pytest.raises(ValueError, match="plays the captors itself"):
        policy(observations, env)
    # Without the env, the observations' shapes say what is wrong.
    flat = t2e.parallel_env(maps="shipped", num_captors=2, observation="flat")
    observations, _ = flat.reset(seed=0)
    with pytest.raises(ValueError, match=r"pass spec observations \(dict with patch and vector\)"):
        policy(observations)
    with pytest.raises(ValueError, match=r"reads \[B, 15\]"):
        policy.logits(np.zeros((1, 48, 48), np.uint8), np.zeros((1, 20), np.float32))
    with pytest.raises(ValueError, match=r"reads \[B, 48, 48\]"):
        policy.logits(np.zeros((1, 12, 12), np.uint8), np.zeros((1, 15), np.float32))


def test_one_policy_object_keeps_one_recurrent_state_per_env(tmp_path):
    # Random weights: the recurrent state moves the actions step by step.
    folder = write_checkpoint(tmp_path / "random", "captors", 2, dict(hidden=32, vector_input="layer_norm"), seed=0)

    def play(policy_for, seeds, steps=40):
        envs = [t2e.parallel_env(maps="shipped", num_captors=2, episode_length=40) for _ in seeds]
        observations = [env.reset(seed=seed)[0] for env, seed in zip(envs, seeds)]
        moves = [[] for _ in envs]
        for _ in range(steps):
            for i, env in enumerate(envs):
                actions = policy_for(i)(observations[i], env)
                moves[i].append(tuple(actions.values()))
                observations[i], *_ = env.step({**actions, "target": 3})
        return moves

    shared = t2e.load_policy(folder)
    together = play(lambda i: shared, (3, 8))
    alone = []
    for seed in (3, 8):
        own = t2e.load_policy(folder)
        alone += play(lambda i: own, [seed])
    assert together == alone
    assert any(len(set(m)) > 1 for m in alone)


def test_state_and_render_need_a_reset_and_render_takes_the_env_s_mode():
    env = t2e.parallel_env(maps="shipped", render_mode="rgb_array")
    with pytest.raises(RuntimeError, match=r"state\(\) before reset\(\).*call reset\(\) first"):
        env.state()
    with pytest.raises(RuntimeError, match=r"render\(\) before reset\(\).*call reset\(\) first"):
        env.render()
    env.reset(seed=0)
    assert env.render("rgb_array").shape[2] == 3
    assert env.render(mode=None).shape[2] == 3
    with pytest.raises(ValueError, match="render_mode='human'"):
        env.render("human")
    assert t2e.parallel_env(maps="shipped").render() is None


FORK_CHILD = """
import os, sys
import t2e
import torch
torch.set_num_threads(2)  # what a 2-core machine starts with; more elsewhere
env = t2e.parallel_env(maps="shipped", num_captors=2, target="ckpt:" + sys.argv[1])
env.reset(seed=0)
for _ in range(30):
    env.step({a: 0 for a in env.agents})
"""


def run_script(code, *args):
    """`code` in a fresh interpreter, so that a hang fails the test."""
    try:
        done = subprocess.run([sys.executable, "-c", textwrap.dedent(code), *map(str, args)],
                              capture_output=True, text=True, timeout=120)
    except subprocess.TimeoutExpired:
        pytest.fail("the script hung (a forked child waiting on its parent's torch threads)")
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_a_child_forked_after_a_loaded_opponent_played_plays_too():
    out = run_script(FORK_CHILD + """
pid = os.fork()
if pid == 0:
    env.reset(seed=1)
    for _ in range(30):
        env.step({a: 0 for a in env.agents})
    print(torch.get_num_threads(), flush=True)
    os._exit(0)
_, status = os.waitpid(pid, 0)
assert status == 0, status
""", TARGET)
    assert out.split() == ["1"]


def test_supersuit_worker_processes_play_a_loaded_opponent_after_the_parent_did():
    pytest.importorskip("supersuit")
    out = run_script(FORK_CHILD + """
import numpy as np
import supersuit as ss
venv = ss.concat_vec_envs_v1(ss.pettingzoo_env_to_vec_env_v1(env), 2, num_cpus=2, base_class="gymnasium")
venv.reset(seed=0)
for _ in range(20):
    *_, infos = venv.step(np.zeros(4, dtype=np.int64))
venv.close()
print("stepped")
""", TARGET)
    assert out.split() == ["stepped"]


@pytest.mark.parametrize(
    "make, side",
    [(t2e.rule_based_target, "target"), (t2e.expert_captors, "captors"), (lambda: t2e.greedy_captors(2), "captors"),
     (lambda: t2e.ScriptedPolicy("random", "target"), "target")],
)
def test_a_scripted_policy_is_an_opponent_as_its_controller_is(make, side):
    policy = make()
    inside = t2e.parallel_env(maps="shipped", episode_length=30, **{side: policy})
    by_name = t2e.parallel_env(maps="shipped", episode_length=30, **{side: policy.name})
    a, _ = inside.reset(seed=5)
    b, _ = by_name.reset(seed=5)
    while inside.agents:
        moves = {x: 0 for x in inside.agents}
        a, *_ = inside.step(moves)
        b, *_ = by_name.step(moves)
        assert all(np.array_equal(a[x]["vector"], b[x]["vector"]) for x in a)
    assert pickle.loads(pickle.dumps(inside))._kwargs[side] == policy.name
    other = "captors" if side == "target" else "target"
    with pytest.raises(ValueError, match=rf"{other} = ScriptedPolicy\(.*a policy of the {side} side"):
        t2e.parallel_env(maps="shipped", **{other: policy})
    venv = t2e.vector_env(2, maps="shipped", seed=1, **{side: policy})
    venv.reset()


def test_a_loaded_policy_of_the_wrong_side_is_named_by_its_folder():
    with pytest.raises(ValueError, match=rf"target = 'ckpt:{CAPTORS}'.*a captors checkpoint, not a target one"):
        t2e.parallel_env(maps="shipped", num_captors=2, target=f"ckpt:{CAPTORS}")
    policy = t2e.load_policy(CAPTORS)
    assert repr(policy) == f"load_policy({str(CAPTORS)!r})"
    with pytest.raises(ValueError, match=rf"target = load_policy\('{CAPTORS}'\): a policy of the captors side"):
        t2e.parallel_env(maps="shipped", num_captors=2, target=policy)
    with pytest.raises(ValueError, match=rf"target = load_policy\('{TARGET}'\): trained with num_captors = 2.*this env has num_captors = 3; make the env with num_captors=2"):
        t2e.parallel_env(maps="shipped", num_captors=3, target=f"ckpt:{TARGET}")


@pytest.mark.parametrize(
    "kwargs, named",
    [
        (dict(wall_rays=10**30), "wall_rays"),
        (dict(wall_rays=2), "wall_rays"),
        (dict(map_cells=10**30), "map_cells"),
        (dict(map_cells=4), "map_cells"),
        (dict(num_captors=10**30), "num_captors"),
        (dict(episode_length=10**30), "episode_length"),
        (dict(episode_length=-1), "episode_length"),
        (dict(speed_ratio=10**400), "speed_ratio"),
    ],
)
def test_huge_or_out_of_range_numbers_are_refused_by_name(kwargs, named):
    with pytest.raises(ValueError, match=rf"^{named} = .*must be"):
        t2e.parallel_env(maps="shipped", **kwargs)
    with pytest.raises(ValueError, match=rf"^{named} = .*must be"):
        t2e.vector_env(2, maps="shipped", **kwargs)


def test_vector_env_names_a_huge_world_count_and_non_string_names():
    with pytest.raises(ValueError, match="num_envs = .*must be between 1 and 65536"):
        t2e.vector_env(10**30, maps="shipped")
    with pytest.raises(TypeError, match="maps = 3"):
        t2e.vector_env(2, maps=3)
    with pytest.raises(TypeError, match="target = 7"):
        t2e.vector_env(2, maps="shipped", target=7)


def test_max_cycles_is_named_by_its_own_name():
    with pytest.raises(ValueError, match="^max_cycles = 0"):
        t2e.parallel_env(maps="shipped", max_cycles=0)
    with pytest.raises(TypeError, match="^max_cycles"):
        t2e.parallel_env(maps="shipped", max_cycles=2.5)


def test_a_pickled_env_with_a_relative_ckpt_path_loads_in_another_folder(tmp_path, monkeypatch):
    shutil.copytree(TARGET, tmp_path / "players" / "target")
    monkeypatch.chdir(tmp_path)
    env = t2e.parallel_env(maps="shipped", num_captors=2, target="ckpt:players/target")
    data = pickle.dumps(env)
    assert env._opponents["target"].folder == tmp_path / "players" / "target"
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    again = pickle.loads(data)
    assert again._kwargs["target"] == f"ckpt:{tmp_path / 'players' / 'target'}"
    a, _ = env.reset(seed=2)
    b, _ = again.reset(seed=2)
    for _ in range(10):
        a, *_ = env.step({x: 0 for x in env.agents})
        b, *_ = again.step({x: 0 for x in again.agents})
    assert all(np.array_equal(a[x]["vector"], b[x]["vector"]) for x in a)


def test_a_copied_aec_env_is_a_new_env_without_an_episode():
    aec = t2e.env(maps="shipped", episode_length=30)
    aec.reset(seed=3)
    aec.step(0)
    for other in (copy.deepcopy(aec), pickle.loads(pickle.dumps(aec)), copy.copy(aec)):
        with pytest.raises(AttributeError, match="before reset"):
            other.agents
        other.reset(seed=3)
        fresh = t2e.env(maps="shipped", episode_length=30)
        fresh.reset(seed=3)
        steps = 0
        for agent in other.agent_iter():
            _, _, term, trunc, _ = other.last()
            other.step(None if term or trunc else 0)
            fresh.step(None if term or trunc else 0)
            steps += 1
        assert steps == 4 * 30 + 4
        assert np.array_equal(other.state(), fresh.state())


def test_a_loaded_policy_pickles_and_plays_an_aec_env():
    policy = pickle.loads(pickle.dumps(t2e.load_policy(TARGET)))
    assert policy.side == "target" and policy.folder == TARGET
    aec = t2e.env(maps="shipped", num_captors=2, episode_length=10)
    aec.reset(seed=1)
    parallel = aec.unwrapped
    observations = {a: aec.observe(a) for a in aec.agents}
    assert set(policy(observations, aec)) == {"target"}
    with pytest.raises(TypeError, match="env = VectorEnv: a loaded policy plays a t2e.parallel_env"):
        policy(observations, t2e.vector_env(1, maps="shipped", num_captors=2, seed=0))
    assert parallel.possible_agents[-1] == "target"


def test_load_policy_names_what_it_was_given():
    with pytest.raises(TypeError, match="folder = None"):
        t2e.load_policy(None)
    with pytest.raises(ValueError, match="side = 'both'"):
        t2e.load_policy(TARGET, side="both")
    with pytest.raises(t2e.torch_policy.PolicyError, match="a target checkpoint, not a captors one"):
        t2e.load_policy(TARGET, side="captors")
    # A file of a checkpoint folder names its folder, as `ckpt:` reads it.
    assert t2e.load_policy(TARGET / "meta.json").folder == TARGET
    policy = t2e.load_policy(os.path.relpath(TARGET))
    assert policy.folder.is_absolute()


def test_more_inputs_named_with_their_fix():
    policy = t2e.load_policy(TARGET)
    env = t2e.parallel_env(maps="shipped", num_captors=2)
    observations, _ = env.reset(seed=0)
    with pytest.raises(ValueError, match=r"observations\['target'\] is a dict of \['patch'\]: pass spec observations"):
        policy({"target": {"patch": observations["target"]["patch"]}}, env)
    with pytest.raises(TypeError, match="observations = list: pass the dict reset"):
        policy(list(observations.values()), env)
    with pytest.raises(ValueError, match="folder = '': .*not an empty string"):
        t2e.load_policy("")
    with pytest.raises(ValueError, match=r"target = 'ckpt:.*use parallel_env\(target="):
        t2e.vector_env(2, maps="shipped", num_captors=2, target=f"ckpt:{TARGET}")
    with pytest.raises(t2e.torch_policy.PolicyError, match="target = 'ckpt:/nowhere': /nowhere: not a folder"):
        t2e.parallel_env(maps="shipped", target="ckpt:/nowhere")
