"""The observation options: each agrees with its space, with the spec's
observation it is made from, and with what the Rust learners' networks
read (the egocentric numbers are checked against the PyTorch actor's own
feature code, which plays exported Rust checkpoints step for step)."""

import pickle

import numpy as np
import pytest

import t2e
from t2e import observations


def run(env, seed=5, steps=40):
    out, _ = env.reset(seed=seed)
    seen = [out]
    rng = np.random.default_rng(seed)
    for _ in range(steps):
        if not env.agents:
            break
        out, *_ = env.step({a: int(rng.integers(t2e.ACTIONS)) for a in env.agents})
        seen.append(out)
    return seen


@pytest.mark.parametrize("kind", observations.KINDS)
@pytest.mark.parametrize("patch_pool", [2, 4])
def test_every_option_is_in_its_space_and_made_from_the_spec(kind, patch_pool):
    spec = run(t2e.parallel_env(maps="shipped"))
    shaped_env = t2e.parallel_env(maps="shipped", observation=kind, patch_pool=patch_pool)
    shaped = run(shaped_env)
    assert len(spec) == len(shaped)
    side = 48 // patch_pool
    for a, b in zip(spec, shaped):
        for agent in shaped_env.possible_agents:
            assert shaped_env.observation_space(agent).contains(b[agent])
            vector, patch = a[agent]["vector"], a[agent]["patch"]
            if kind == "spec":
                assert np.array_equal(b[agent]["vector"], vector) and np.array_equal(b[agent]["patch"], patch)
                continue
            if kind == "image":
                # The whole patch in image bounds, channel last; patch_pool does not apply.
                assert np.array_equal(b[agent]["vector"], vector)
                assert np.array_equal(b[agent]["patch"], patch[..., None] * np.uint8(255))
                continue
            pooled = patch.reshape(side, patch_pool, side, patch_pool).max(axis=(1, 3))
            ego = observations.egocentric(vector[None])[0]
            if kind == "egocentric":
                assert np.array_equal(b[agent]["patch"], pooled) and np.array_equal(b[agent]["vector"], ego)
            else:
                assert np.array_equal(b[agent], np.concatenate([ego, pooled.ravel().astype(np.float32)]))


def test_the_egocentric_vector_is_the_rust_learners_input():
    torch = pytest.importorskip("torch")
    from t2e.torch_policy import _vector_features

    vectors = np.concatenate([s["captor_1"]["vector"][None] for s in run(t2e.parallel_env(maps="shipped"))])
    rng = np.random.default_rng(1)
    vectors = np.concatenate([vectors, rng.normal(scale=4, size=vectors.shape).astype(np.float32)])
    mine = observations.egocentric(vectors)
    theirs = _vector_features(torch.from_numpy(vectors), 1, "egocentric").numpy()
    assert mine.shape == (len(vectors), 6 + 9 * 3)
    np.testing.assert_allclose(mine, theirs, rtol=1e-5, atol=1e-6)


def test_a_target_straight_ahead_is_ahead_whatever_the_heading():
    # A captor at (1, 2) heading pi/2 (facing +y); the target 3 m along +y.
    vector = np.zeros((1, 10), dtype=np.float32)
    vector[0, 2:5] = (1.0, 2.0, np.pi / 2)
    vector[0, 7:9] = (0.0, 3.0)
    ego = observations.egocentric(vector)[0]
    forward, left, distance, bearing_cos, bearing_sin = ego[6:11]
    assert forward == pytest.approx(3 / 8) and left == pytest.approx(0, abs=1e-6)
    assert distance == pytest.approx(3 / 8) and (bearing_cos, bearing_sin) == pytest.approx((1, 0), abs=1e-6)


def test_options_travel_with_a_pickled_env_and_bad_ones_are_named():
    env = t2e.parallel_env(maps="shipped", observation="flat", patch_pool=6)
    copy = pickle.loads(pickle.dumps(env))
    assert copy.observation_space("target") == env.observation_space("target")
    assert env.observation_space("target").shape == (6 + 9 * 3 + 64,)
    with pytest.raises(ValueError, match="observation = 'pixels'"):
        t2e.parallel_env(observation="pixels")
    for pool in (5, 0, True, 2.0):
        with pytest.raises(ValueError, match="patch_pool"):
            t2e.parallel_env(patch_pool=pool)
