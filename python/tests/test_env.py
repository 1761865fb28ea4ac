"""The env's own promises: spaces, same seed same episode, episodes that
end, and bad input refused with a Python exception naming the argument."""

import numpy as np
import pytest

import t2e


def make(**kw):
    args = dict(maps="shipped", num_captors=3, episode_length=40)
    args.update(kw)
    return t2e.parallel_env(**args)


def rollout(env, seed, steps):
    obs, infos = env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    trace = [(env.map_name, {a: o["vector"].copy() for a, o in obs.items()})]
    for _ in range(steps):
        if not env.agents:
            break
        actions = {a: int(rng.integers(t2e.ACTIONS)) for a in env.agents}
        obs, rewards, terms, truncs, infos = env.step(actions)
        trace.append((rewards, {a: o["vector"].copy() for a, o in obs.items()}))
    return trace


def test_agents_spaces_and_observations():
    env = make()
    assert env.possible_agents == ["captor_0", "captor_1", "captor_2", "target"]
    obs, infos = env.reset(seed=3)
    for agent in env.possible_agents:
        assert env.observation_space(agent).contains(obs[agent])
        assert obs[agent]["vector"].shape == (5 + 5 * 3,)
        assert obs[agent]["patch"].shape == (48, 48)
        assert set(infos[agent]) == {"map_index", "captured"}
    assert env.map_names[infos["target"]["map_index"]] == env.map_name


def test_same_seed_same_episode_and_other_seeds_differ():
    a = rollout(make(), 11, 30)
    b = rollout(make(), 11, 30)
    c = rollout(make(), 12, 30)
    assert len(a) == len(b)
    for (ra, va), (rb, vb) in zip(a, b):
        assert ra == rb
        for agent in va:
            np.testing.assert_array_equal(va[agent], vb[agent])
    assert any(
        not np.array_equal(va[ag], vc[ag]) for (_, va), (_, vc) in zip(a, c) for ag in va
    )


def test_an_episode_truncates_at_its_length_and_then_refuses_to_step():
    env = make(episode_length=5)
    env.reset(seed=0)
    for _ in range(5):
        assert env.agents
        _, _, terms, truncs, _ = env.step({a: 4 for a in env.agents})
    assert env.agents == [] and all(truncs.values()) and not any(terms.values())
    with pytest.raises(RuntimeError, match="reset"):
        env.step({a: 0 for a in env.possible_agents})


@pytest.mark.parametrize(
    "kwargs, error, named",
    [
        (dict(maps="no-such-maps"), ValueError, "maps"),
        (dict(maps="small"), ValueError, "maps"),  # the test set, under held-out
        (dict(num_captors=0), ValueError, "num_captors"),
        (dict(num_captors=2.5), TypeError, "num_captors"),
        (dict(speed_ratio=float("nan")), ValueError, "speed_ratio"),
        (dict(speed_ratio=-1.0), ValueError, "speed_ratio"),
        (dict(episode_length=0), ValueError, "episode_length"),
        (dict(protocol="heldout"), ValueError, "protocol"),
        (dict(render_mode="rgb"), ValueError, "render_mode"),
    ],
)
def test_bad_settings_are_refused_naming_the_argument(kwargs, error, named):
    with pytest.raises(error, match=named):
        make(**kwargs)


def test_bad_actions_and_seeds_are_refused_naming_them():
    env = make()
    with pytest.raises(ValueError, match="seed"):
        env.reset(seed=-1)
    with pytest.raises(RuntimeError, match="reset"):
        env.step({a: 0 for a in env.possible_agents})
    env.reset(seed=1)
    good = {a: 0 for a in env.agents}
    for agent, bad in [
        ("captor_0", 5),
        ("captor_1", -1),
        ("target", float("nan")),
        ("target", 1.5),
        ("captor_2", np.zeros(3, dtype=np.int64)),
        ("captor_0", "forward"),
    ]:
        with pytest.raises(ValueError, match=agent):
            env.step({**good, agent: bad})
    with pytest.raises(ValueError, match="missing"):
        env.step({"captor_0": 0})
    with pytest.raises(ValueError, match="unknown"):
        env.step({**good, "captor_9": 0})
    # After the refusals the episode goes on as if nothing happened.
    obs, *_ = env.step(good)
    assert set(obs) == set(env.possible_agents)


def test_frames_show_the_episode_as_it_goes():
    env = make(render_mode="rgb_array")
    env.reset(seed=4)
    first = env.render()
    assert first.ndim == 3 and first.shape[2] == 3 and first.dtype == np.uint8
    for _ in range(10):
        env.step({a: 0 for a in env.agents})
    later = env.render()
    assert later.shape == first.shape and not np.array_equal(later, first)
    # The target is drawn as a red disc of its 0.2 m radius.
    for frame in (first, later):
        assert np.all(frame == [225, 35, 35], axis=-1).sum() > 50
    assert make().render() is None
