"""What trainers and vector wrappers need of an env, without them:
pickling and copying (SuperSuit and multiprocessing copy envs that way),
building and stepping in a child made by fork after the parent built an
env (Python's default start method on Linux), numeric infos, PettingZoo's
AEC API and `max_cycles`, checked with PettingZoo's own tests."""

import copy
import multiprocessing as mp
import pickle

import numpy as np
import pytest
from pettingzoo.test import api_test, max_cycles_test

import t2e


def play(env, seed, steps=25):
    obs, _ = env.reset(seed=seed)
    out = [obs["target"]["vector"].copy()]
    rng = np.random.default_rng(seed)
    for _ in range(steps):
        if not env.agents:
            break
        obs, *_ = env.step({a: int(rng.integers(t2e.ACTIONS)) for a in env.agents})
        out.append(obs["target"]["vector"].copy())
    return np.stack(out)


def test_a_pickled_or_copied_env_plays_the_same_episodes():
    env = t2e.parallel_env(maps="shipped", episode_length=30, asz_info=True)
    env.reset(seed=4)
    for other in (pickle.loads(pickle.dumps(env)), copy.deepcopy(env), copy.copy(env)):
        assert other is not env and other._kwargs == env._kwargs
        assert np.array_equal(play(other, 9), play(env, 9))
    # The random state goes along: the next drawn episode is the same.
    a, b = t2e.parallel_env(maps="shipped"), None
    a.reset(seed=1)
    b = pickle.loads(pickle.dumps(a))
    a.reset()
    b.reset()
    assert a._env.seed == b._env.seed


def test_the_core_envs_pickle_from_their_arguments():
    core = t2e.Env("shipped", 2, 1.2, "held-out", 40, False)
    again = pickle.loads(pickle.dumps(core))
    assert (again.vector_len, again.episode_length, again.map_names) == (core.vector_len, core.episode_length, core.map_names)
    venv = t2e.vector_env(3, maps="shipped", num_captors=2, seed=17, target="heuristic")
    twin = copy.deepcopy(venv)
    assert twin.seed == 17 and twin.num_envs == 3
    a, _ = venv.reset()
    b, _ = twin.reset()
    assert np.array_equal(a, b)
    zeros = np.zeros((3, 3), dtype=np.int64)
    assert np.array_equal(venv.step(zeros)[0], twin.step(zeros)[0])


def _child(queue):
    try:
        env = t2e.parallel_env(maps="generated:2")
        env.reset(seed=1)
        env.step({a: 0 for a in env.agents})
        venv = t2e.vector_env(4, maps="shipped", seed=2)
        venv.reset()
        venv.step(np.zeros((4, 4), dtype=np.int64))
        queue.put("ok")
    except Exception as e:  # noqa: BLE001 - reported to the parent
        queue.put(repr(e))


def test_a_forked_child_builds_and_steps_envs():
    parent = t2e.vector_env(8, maps="generated:2", seed=1)
    parent.reset()
    parent.step(np.zeros((8, 4), dtype=np.int64))
    ctx = mp.get_context("fork")
    queue = ctx.Queue()
    child = ctx.Process(target=_child, args=(queue,))
    child.start()
    child.join(120)
    if child.is_alive():
        child.kill()
        pytest.fail("the forked child hung")
    assert queue.get(timeout=5) == "ok"


def test_infos_are_numbers_and_the_map_is_named_by_index():
    env = t2e.parallel_env(maps="shipped", episode_length=5)
    _, infos = env.reset(seed=2)
    assert infos["target"] == {"map_index": infos["target"]["map_index"], "captured": False}
    assert env.map_names[infos["target"]["map_index"]] == env.map_name
    while env.agents:
        _, _, terminations, _, infos = env.step({a: 0 for a in env.agents})
        assert set(infos["captor_0"]) == {"map_index", "captured"}
        assert all(isinstance(v, (bool, int, float)) for v in infos["captor_0"].values())
        assert infos["captor_0"]["captured"] == terminations["captor_0"]
    # A reset's `captured` repeats the last step's, so a merge of the two keeps it.
    trapped = t2e.parallel_env(maps="shipped", target="still", episode_length=500)
    trapped.reset(seed=4)
    while trapped.agents:
        *_, infos = trapped.step({a: 0 for a in trapped.agents})
    last = infos["captor_0"]["captured"]
    _, infos = trapped.reset()
    assert infos["captor_0"]["captured"] == last
    *_, infos = trapped.step({a: 0 for a in trapped.agents})
    assert infos["captor_0"]["captured"] is False
    with_asz = t2e.parallel_env(maps="shipped", asz_info=True)
    _, infos = with_asz.reset(seed=2)
    assert infos["target"]["asz_area"] > 0


def test_pettingzoo_aec_api_and_max_cycles():
    api_test(t2e.env(maps="shipped", episode_length=30), num_cycles=40)
    max_cycles_test(t2e)
    assert t2e.parallel_env(max_cycles=7).max_cycles == 7
    with pytest.raises(ValueError, match="max_cycles"):
        t2e.parallel_env(max_cycles=7, episode_length=9)


def test_a_built_in_opponent_plays_as_the_same_controller_outside():
    inside = t2e.parallel_env(maps="shipped", episode_length=40, target="heuristic")
    assert inside.possible_agents == ["captor_0", "captor_1", "captor_2"]
    outside = t2e.parallel_env(maps="shipped", episode_length=40)
    rule = t2e.rule_based_target()
    a, _ = inside.reset(seed=5)
    b, _ = outside.reset(seed=5)
    rng = np.random.default_rng(0)
    while inside.agents:
        moves = {c: int(rng.integers(t2e.ACTIONS)) for c in inside.agents}
        a, ra, *_ = inside.step(moves)
        b, rb, *_ = outside.step({**moves, **rule(outside)})
        assert all(np.array_equal(a[c]["vector"], b[c]["vector"]) and ra[c] == rb[c] for c in a)
    assert not outside.agents
    again = pickle.loads(pickle.dumps(inside))
    assert again.possible_agents == inside.possible_agents
    with pytest.raises(ValueError, match="name"):
        t2e.parallel_env(target="nobody")
    with pytest.raises(ValueError, match="no agent"):
        t2e.parallel_env(target="heuristic", captors="greedy")


def test_state_for_a_centralised_critic():
    from pettingzoo.test import state_test

    env = t2e.parallel_env(maps="shipped", episode_length=20)
    env.reset(seed=3)
    state = env.state()
    assert env.state_space.contains(state)
    assert state.shape == (5 * 4 + 1,)
    x, y, _, _, heading = env._env.state()[15:20]
    assert (x, y) == pytest.approx(env._env.poses[3][:2], abs=1e-5)
    state_test(t2e.env(maps="shipped", episode_length=20), t2e.parallel_env(maps="shipped", episode_length=20))
