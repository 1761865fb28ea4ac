"""Sight (wall rays appended to each vector, `net.sight`) works the same in
the Python env as in Rust: the spaces and arrays carry the rays, a copy
keeps them, a player trained with them plays the Rust controller's
episodes in Python, and one fed other inputs is refused by name."""

import csv
import pickle
import subprocess
from pathlib import Path

import numpy as np
import pytest

import t2e

ROOT = Path(__file__).resolve().parents[2]
BINARY = ROOT / "target" / "release" / "t2e-league"

CONFIG = """
name = "sighted"
protocol = "held-out"
seed = 3
total_env_steps = 3200
num_envs = 8
rollout_steps = 50
checkpoint_every = 1
maps = "generated:2"

[env]
num_captors = 2

[captors]
play = "mappo"

[captors.net]
hidden = 16
conv_channels = [4, 4]
patch_pool = 4
vector_input = "egocentric"

[captors.net.sight]
wall_rays = 8
"""


@pytest.fixture(scope="module")
def sighted(tmp_path_factory):
    """A small captor team trained with 8 wall rays."""
    root = tmp_path_factory.mktemp("sighted")
    (root / "config.toml").write_text(CONFIG)
    subprocess.run(
        [str(BINARY), "train", "--config", str(root / "config.toml"), "--out", str(root / "run"), "--quiet"],
        check=True, capture_output=True, cwd=ROOT,
    )
    folders = sorted((root / "run" / "checkpoints").glob("captors-*"))
    assert folders, "training wrote no checkpoint"
    return folders[-1]


def test_rays_follow_the_spec_vector_in_every_observation_kind():
    plain = t2e.parallel_env(maps="shipped", num_captors=2)
    seen = t2e.parallel_env(maps="shipped", num_captors=2, wall_rays=12)
    a, _ = plain.reset(seed=5)
    b, _ = seen.reset(seed=5)
    for agent in plain.agents:
        assert b[agent]["vector"].shape == (15 + 12,)
        assert seen.observation_space(agent)["vector"].shape == (27,)
        # The spec's numbers are untouched; the rays are distances / 16 m.
        np.testing.assert_array_equal(a[agent]["vector"], b[agent]["vector"][:15])
        rays = b[agent]["vector"][15:]
        assert ((rays > 0) & (rays <= 1)).all(), rays
        np.testing.assert_array_equal(a[agent]["patch"], b[agent]["patch"])
    for kind, width in (("egocentric", 6 + 9 * 2 + 12), ("flat", 6 + 9 * 2 + 12 + 144)):
        env = t2e.parallel_env(maps="shipped", num_captors=2, wall_rays=12, observation=kind, patch_pool=4)
        obs, _ = env.reset(seed=5)
        row = obs["target"]["vector"] if kind == "egocentric" else obs["target"]
        assert row.shape == (width,)
        assert env.observation_space("target").contains(obs["target"])
        # The rays come after the egocentric numbers, as they are.
        np.testing.assert_array_equal(row[6 + 18 : 6 + 18 + 12], b["target"]["vector"][15:])
    copy = pickle.loads(pickle.dumps(seen))
    assert copy.wall_rays == 12
    c, _ = copy.reset(seed=5)
    np.testing.assert_array_equal(c["target"]["vector"], b["target"]["vector"])
    venv = t2e.vector_env(2, maps="shipped", num_captors=2, seed=1, wall_rays=12)
    vectors, _ = venv.reset()
    assert vectors.shape == (2, 3, 27)
    assert pickle.loads(pickle.dumps(venv)).wall_rays == 12


@pytest.mark.parametrize("rays", [1, 3, 73, -1])
def test_a_ray_count_outside_the_range_is_refused_by_name(rays):
    with pytest.raises(ValueError, match="wall_rays"):
        t2e.parallel_env(maps="shipped", wall_rays=rays)


def test_a_sighted_player_plays_the_rust_episodes_and_needs_its_rays(sighted, tmp_path):
    torch = pytest.importorskip("torch")  # noqa: F841
    policy = t2e.load_policy(sighted)
    assert policy.wall_rays == 8
    out = tmp_path / "eval"
    subprocess.run(
        [str(BINARY), "eval", "--captors", f"ckpt:{sighted}", "--target", "heuristic", "--maps", "shipped",
         "--k", "2", "--episodes", "3", "--seed", "4", "--out", str(out)],
        check=True, capture_output=True, cwd=ROOT,
    )
    rows = [row for path in sorted(out.rglob("episodes.csv")) for row in csv.DictReader(open(path))]
    assert len(rows) == 3
    env = t2e.parallel_env(maps="shipped", num_captors=2, wall_rays=8)
    target = t2e.ScriptedPolicy("heuristic", "target")
    for row in rows:
        observations, _ = env.reset(seed=int(row["seed"]))
        steps, captured = 0, False
        while env.agents:
            observations, _, _, _, infos = env.step({**policy(observations, env), **target(env)})
            steps += 1
            captured = infos["target"]["captured"]
        assert (steps, captured) == (int(row["steps"]), row["captured"] == "true"), row
    blind = t2e.parallel_env(maps="shipped", num_captors=2)
    observations, _ = blind.reset(seed=1)
    with pytest.raises(ValueError, match="wall_rays=8"):
        policy(observations, blind)
    with pytest.raises(ValueError, match="wall_rays = 8"):
        t2e.parallel_env(maps="shipped", num_captors=2, captors=f"ckpt:{sighted}")
    # As an opponent inside an env with its rays, it plays.
    env = t2e.parallel_env(maps="shipped", num_captors=2, wall_rays=8, captors=f"ckpt:{sighted}")
    env.reset(seed=2)
    env.step({"target": 0})
