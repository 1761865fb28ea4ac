"""Python never gives a wrong result for a bad input, and never crashes the
interpreter: arrays in any memory order, panics as exceptions, sizes
bounded where memory would run out, strings and bools where numbers belong
refused. Each test failed before its fix."""

import numpy as np
import pytest

import t2e


def test_vector_env_reads_actions_in_index_order_whatever_the_memory_order():
    def run(make_actions):
        venv = t2e.vector_env(4, maps="shipped", num_captors=3, episode_length=60, seed=11)
        venv.reset()
        rng = np.random.default_rng(5)
        out = []
        for _ in range(30):
            actions = rng.integers(0, t2e.ACTIONS, size=(4, 4)).astype(np.int64)
            vectors, *_ = venv.step(make_actions(actions))
            out.append(vectors.copy())
        return np.stack(out)

    plain = run(lambda a: a)
    fortran = run(np.asfortranarray)
    transposed = run(lambda a: np.ascontiguousarray(a.T).T)
    strided = run(lambda a: np.repeat(a, 2, axis=1)[:, ::2])
    assert np.array_equal(plain, fortran)
    assert np.array_equal(plain, transposed)
    assert np.array_equal(plain, strided)


def test_env_step_reads_a_strided_action_vector_in_index_order():
    def run(make_actions):
        env = t2e.Env("shipped", 3, 1.0, "held-out", 40, False)
        env.reset(7)
        a = np.array([0, 1, 2, 4], dtype=np.int64)
        vectors, *_ = env.step(make_actions(a))
        return vectors

    assert np.array_equal(run(lambda a: a), run(lambda a: np.repeat(a, 2)[::2]))
    assert np.array_equal(run(lambda a: a), run(lambda a: a[::-1].copy()[::-1]))


def test_asz_area_refuses_what_it_would_misread_and_never_panics():
    env = t2e.Env("shipped", 3, 1.0, "held-out", 40, False)
    with pytest.raises(RuntimeError, match="before reset"):
        env.asz_area()
    env.reset(3)
    poses = env.poses
    captors = [(x, y) for x, y, _ in poses[:3]]
    target = poses[3][:2]
    assert t2e.asz_area(env, captors, target) > 0
    with pytest.raises(ValueError, match="at most 8 captors"):
        t2e.asz_area(env, captors * 100, target)
    with pytest.raises(ValueError, match="not on a free cell"):
        t2e.asz_area(env, captors, (500.0, 500.0))
    with pytest.raises(ValueError, match="not on a free cell"):
        t2e.asz_area(env, captors, (-500.0, 0.0))


@pytest.mark.parametrize("k", [9, 12, 14, 32])
def test_captor_counts_that_cannot_be_placed_are_refused_at_construction(k):
    with pytest.raises(ValueError, match="num_captors"):
        t2e.parallel_env(maps="shipped", num_captors=k)
    with pytest.raises(ValueError, match="num_captors"):
        t2e.vector_env(2, maps="shipped", num_captors=k)


def test_the_most_captors_reset_and_step_on_every_seed_tried():
    venv = t2e.vector_env(8, maps="shipped", num_captors=8, episode_length=30, seed=2)
    venv.reset()
    zeros = np.zeros((8, 9), dtype=np.int64)
    for _ in range(200):  # several auto-resets per world
        venv.step(zeros)


def test_sizes_past_memory_are_refused_not_aborted():
    with pytest.raises(ValueError, match="num_envs"):
        t2e.vector_env(65536, maps="shipped", num_captors=8)
    with pytest.raises(ValueError, match="1000"):
        t2e.parallel_env(maps="generated:10000")
    with pytest.raises(ValueError, match="generated maps"):
        t2e.parallel_env(maps="generated:1000,generated:1000@2000")


def test_bools_and_strings_are_not_read_as_numbers_or_flags():
    with pytest.raises(TypeError, match="asz_info"):
        t2e.parallel_env(maps="shipped", asz_info="no")
    with pytest.raises(TypeError, match="num_envs"):
        t2e.vector_env(True, maps="shipped")
    with pytest.raises(TypeError, match="seed"):
        t2e.vector_env(2, maps="shipped", seed=1.5)


def test_vector_env_without_a_seed_draws_one_and_says_which():
    a, b = t2e.vector_env(2, maps="shipped"), t2e.vector_env(2, maps="shipped")
    assert a.seed != b.seed  # 2**-64 to fail by chance
    again = t2e.vector_env(2, maps="shipped", seed=a.seed)
    va, _ = a.reset()
    vb, _ = again.reset()
    assert np.array_equal(va, vb)


def test_the_action_error_names_the_actions_there_are():
    env = t2e.parallel_env(maps="shipped")
    env.reset(seed=0)
    with pytest.raises(ValueError, match="from 0 to 4"):
        env.step({a: 5 for a in env.agents})


def test_more_inputs_that_were_misread():
    env = t2e.Env("shipped", 3, 1.0, "held-out", 40, False)
    with pytest.raises(RuntimeError, match="before env.reset"):
        t2e.asz_area(env, [(0.0, 0.0)], (1.0, 1.0))
    with pytest.raises(ValueError, match="bool"):
        env.reset(True)
    env.reset(3)
    poses = env.poses
    captors = [(x, y) for x, y, _ in poses[:3]]
    target = poses[3][:2]
    with pytest.raises(ValueError, match=r"captors\[1\]"):
        t2e.asz_area(env, [captors[0], (-500.0, -500.0), captors[2]], target)
    with pytest.raises(TypeError, match="speed_ratio"):
        t2e.vector_env(2, maps="shipped", speed_ratio=True)
    with pytest.raises(TypeError, match="coarsening"):
        t2e.greedy_captors(True)
    with pytest.raises(ValueError, match="captor_7"):
        t2e.parallel_env(maps="shipped").observation_space("captor_7")
    assert t2e.VectorEnv(2, "shipped").seed != t2e.VectorEnv(2, "shipped").seed
    # A list of map sets is their union.
    both = t2e.parallel_env(maps="shipped:small,shipped:large")
    assert set(both._env.map_names) == set(t2e.parallel_env(maps="shipped:small")._env.map_names) | set(
        t2e.parallel_env(maps="shipped:large")._env.map_names
    )


def test_one_scripted_policy_plays_two_envs_as_it_plays_each_alone():
    def alone(seed):
        env = t2e.parallel_env(maps="shipped", episode_length=30)
        policy = t2e.ScriptedPolicy("random", "target")
        env.reset(seed=seed)
        moves = []
        while env.agents:
            a = policy(env)
            moves.append(a["target"])
            env.step({**{c: 3 for c in env.agents if c != "target"}, **a})
        return moves

    shared = t2e.ScriptedPolicy("random", "target")
    envs = [t2e.parallel_env(maps="shipped", episode_length=30) for _ in range(2)]
    for env, seed in zip(envs, (1, 2)):
        env.reset(seed=seed)
    moves = [[], []]
    while envs[0].agents or envs[1].agents:
        for i, env in enumerate(envs):
            if env.agents:
                a = shared(env)
                moves[i].append(a["target"])
                env.step({**{c: 3 for c in env.agents if c != "target"}, **a})
    assert moves == [alone(1), alone(2)]
    assert len(set(moves[0])) > 1
