"""Sight (wall rays and the coarse map appended to each vector,
`net.sight`) works the same in the Python env as in Rust: the spaces and
arrays carry them, a copy keeps them, a player trained with them plays the
Rust controller's episodes in Python, and one fed other inputs is refused
by name."""

import csv
import pickle
import subprocess
from pathlib import Path

import numpy as np
import pytest

import t2e
from test_load_policy import reseal

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


# The same team with 4 rays and an 8 x 8 map.
MAPPED = CONFIG.replace('name = "sighted"', 'name = "mapped"').replace("wall_rays = 8", "wall_rays = 4\nmap_cells = 8")


def _train(root: Path, config: str) -> Path:
    (root / "config.toml").write_text(config)
    subprocess.run(
        [str(BINARY), "train", "--config", str(root / "config.toml"), "--out", str(root / "run"), "--quiet"],
        check=True, capture_output=True, cwd=ROOT,
    )
    folders = sorted((root / "run" / "checkpoints").glob("captors-*"))
    assert folders, "training wrote no checkpoint"
    return folders[-1]


@pytest.fixture(scope="module")
def sighted(tmp_path_factory):
    """A small captor team trained with 8 wall rays."""
    return _train(tmp_path_factory.mktemp("sighted"), CONFIG)


@pytest.fixture(scope="module")
def mapped(tmp_path_factory):
    """A small captor team trained with 4 wall rays and an 8 x 8 map."""
    return _train(tmp_path_factory.mktemp("mapped"), MAPPED)


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


def _rust_episodes(player: Path, tmp_path: Path, episodes: int, length: int):
    """`episodes` episodes of `length` steps of `player` (2 captors) against
    the rule-based target, as the Rust `eval` plays them: rows of its
    episodes.csv."""
    out = tmp_path / "eval"
    subprocess.run(
        [str(BINARY), "eval", "--captors", f"ckpt:{player}", "--target", "heuristic", "--maps", "shipped",
         "--k", "2", "--episodes", str(episodes), "--episode-length", str(length), "--seed", "4", "--out", str(out)],
        check=True, capture_output=True, cwd=ROOT,
    )
    rows = [row for path in sorted(out.rglob("episodes.csv")) for row in csv.DictReader(open(path))]
    assert len(rows) == episodes
    return rows


def _map_of(vector: np.ndarray, spec: int, rays: int, cells: int) -> np.ndarray:
    """The coarse map's four channels [4, cells, cells] of one vector."""
    tail = vector[spec + rays :]
    assert tail.shape == (4 * cells * cells,)
    return tail.reshape(4, cells, cells)


@pytest.mark.parametrize("cells", [8, 16, 32])
def test_the_map_follows_the_rays_in_every_observation_kind(cells):
    k, spec, rays = 3, 20, 12
    extra = 4 * cells * cells
    seen = t2e.parallel_env(maps="shipped", num_captors=k, wall_rays=rays)
    mapped = t2e.parallel_env(maps="shipped", num_captors=k, wall_rays=rays, map_cells=cells)
    assert mapped.map_cells == cells and mapped._env.map_cells == cells
    assert mapped._env.vector_len == spec + rays + extra
    a, _ = seen.reset(seed=7)
    b, _ = mapped.reset(seed=7)
    for agent in mapped.agents:
        assert mapped.observation_space(agent)["vector"].shape == (spec + rays + extra,)
        assert mapped.observation_space(agent).contains(b[agent])
        # The spec's numbers and the rays are untouched; the map follows.
        np.testing.assert_array_equal(a[agent]["vector"], b[agent]["vector"][: spec + rays])
        np.testing.assert_array_equal(a[agent]["patch"], b[agent]["patch"])
        walls, captors, target, me = _map_of(b[agent]["vector"], spec, rays, cells)
        assert ((walls >= 0) & (walls <= 1)).all()
        # The shipped maps have walls and free space at every size.
        assert 0 < walls.sum() < cells * cells
        assert captors.sum() == k and (captors == np.round(captors)).all()
        assert target.sum() == 1 and set(np.unique(target)) <= {0.0, 1.0}
        assert me.sum() == 1 and set(np.unique(me)) <= {0.0, 1.0}
        # "Self" is where this robot is: the target's cell for the target,
        # a cell holding a captor for a captor.
        if agent == "target":
            np.testing.assert_array_equal(me, target)
        else:
            assert captors[me == 1].item() >= 1
    # Every captor's map is the same but for its "self" channel.
    maps = [_map_of(b[f"captor_{i}"]["vector"], spec, rays, cells) for i in range(k)]
    for other in maps[1:]:
        np.testing.assert_array_equal(other[:3], maps[0][:3])
    for kind, width in (("egocentric", 6 + 9 * k + rays + extra), ("flat", 6 + 9 * k + rays + extra + 144)):
        env = t2e.parallel_env(maps="shipped", num_captors=k, wall_rays=rays, map_cells=cells, observation=kind, patch_pool=4)
        assert env.map_cells == cells
        obs, _ = env.reset(seed=7)
        row = obs["target"]["vector"] if kind == "egocentric" else obs["target"]
        assert row.shape == (width,)
        assert env.observation_space("target").contains(obs["target"])
        # The rays and the map come after the egocentric numbers, as they are.
        start = 6 + 9 * k
        np.testing.assert_array_equal(row[start : start + rays + extra], b["target"]["vector"][spec:])
    venv = t2e.vector_env(2, maps="shipped", num_captors=k, seed=1, wall_rays=rays, map_cells=cells)
    vectors, _ = venv.reset()
    assert vectors.shape == (2, k + 1, spec + rays + extra)
    assert venv.map_cells == cells and venv.wall_rays == rays
    for world in vectors:
        for vector in world:
            channels = _map_of(vector, spec, rays, cells)
            assert [channels[c].sum() for c in (1, 2, 3)] == [k, 1, 1]


def test_a_map_of_0_cells_is_the_observation_without_one():
    for kind in ("spec", "egocentric", "flat"):
        plain = t2e.parallel_env(maps="shipped", num_captors=2, wall_rays=8, observation=kind)
        zero = t2e.parallel_env(maps="shipped", num_captors=2, wall_rays=8, map_cells=0, observation=kind)
        assert zero.map_cells == 0
        assert zero.observation_space("target") == plain.observation_space("target")
        a, _ = plain.reset(seed=3)
        b, _ = zero.reset(seed=3)
        for agent in plain.agents:
            x, y = (a[agent], b[agent]) if kind == "flat" else (a[agent]["vector"], b[agent]["vector"])
            assert x.tobytes() == y.tobytes()


def test_a_copy_keeps_the_map():
    env = t2e.parallel_env(maps="shipped", num_captors=2, wall_rays=4, map_cells=12, observation="flat")
    first, _ = env.reset(seed=9)
    copy = pickle.loads(pickle.dumps(env))
    assert (copy.wall_rays, copy.map_cells) == (4, 12)
    assert copy.observation_space("target") == env.observation_space("target")
    again, _ = copy.reset(seed=9)
    for agent in env.agents:
        np.testing.assert_array_equal(first[agent], again[agent])
    core = pickle.loads(pickle.dumps(env._env))
    assert (core.wall_rays, core.map_cells, core.vector_len) == (4, 12, env._env.vector_len)
    venv = t2e.vector_env(2, maps="shipped", num_captors=2, seed=1, map_cells=8)
    vectors, _ = venv.reset()
    copy = pickle.loads(pickle.dumps(venv))
    assert (copy.wall_rays, copy.map_cells, copy.vector_len) == (0, 8, 15 + 256)
    np.testing.assert_array_equal(copy.reset()[0], vectors)


@pytest.mark.parametrize("cells", [1, 5, 7, 33, 64, -1])
def test_a_map_size_outside_the_range_is_refused_by_name(cells):
    with pytest.raises(ValueError, match=r"map_cells = -?\d+: must be 0 \(no map\) or between 8 and 32"):
        t2e.parallel_env(maps="shipped", map_cells=cells)
    with pytest.raises(ValueError, match="map_cells"):
        t2e.vector_env(2, maps="shipped", map_cells=cells)
    with pytest.raises(ValueError, match="map_cells"):
        t2e.Env("shipped", wall_rays=12, map_cells=cells)


def test_a_map_size_that_is_not_an_integer_is_refused_by_name():
    with pytest.raises(TypeError, match="map_cells"):
        t2e.parallel_env(maps="shipped", map_cells=8.0)
    with pytest.raises(TypeError, match="map_cells"):
        t2e.vector_env(2, maps="shipped", map_cells=True)


def test_a_mapped_player_plays_the_rust_episodes_and_needs_its_map(mapped, sighted, tmp_path):
    torch = pytest.importorskip("torch")  # noqa: F841
    policy = t2e.load_policy(mapped)
    assert (policy.wall_rays, policy.map_cells, policy.vector_len) == (4, 8, 15 + 4 + 256)
    # Shorter episodes than the rays' test: the map's check is the same.
    env = t2e.parallel_env(maps="shipped", num_captors=2, wall_rays=4, map_cells=8, episode_length=150)
    target = t2e.ScriptedPolicy("heuristic", "target")
    for row in _rust_episodes(mapped, tmp_path, episodes=2, length=150):
        observations, _ = env.reset(seed=int(row["seed"]))
        steps, captured = 0, False
        while env.agents:
            observations, _, _, _, infos = env.step({**policy(observations, env), **target(env)})
            steps += 1
            captured = infos["target"]["captured"]
        assert (steps, captured) == (int(row["steps"]), row["captured"] == "true"), row
    # Fed the rays without the map, it says what it needs.
    rays_only = t2e.parallel_env(maps="shipped", num_captors=2, wall_rays=4)
    observations, _ = rays_only.reset(seed=1)
    with pytest.raises(ValueError, match="wall_rays=4, map_cells=8"):
        policy(observations, rays_only)
    # As an opponent, in an env without its map or with another one.
    for cells in (0, 16):
        with pytest.raises(ValueError, match=f"map_cells = 8 .*net.sight.*this env has map_cells = {cells}"):
            t2e.parallel_env(maps="shipped", num_captors=2, wall_rays=4, map_cells=cells, captors=f"ckpt:{mapped}")
    # A player without a map is refused by an env with one.
    with pytest.raises(ValueError, match="map_cells = 0 .*this env has map_cells = 8"):
        t2e.parallel_env(maps="shipped", num_captors=2, wall_rays=8, map_cells=8, captors=f"ckpt:{sighted}")
    # As an opponent inside an env with its rays and map, it plays.
    env = t2e.parallel_env(maps="shipped", num_captors=2, wall_rays=4, map_cells=8, captors=f"ckpt:{mapped}")
    env.reset(seed=2)
    env.step({"target": 0})
    assert pickle.loads(pickle.dumps(env)).map_cells == 8


def test_a_meta_json_with_a_map_size_outside_the_range_is_refused(mapped, tmp_path):
    pytest.importorskip("torch")
    import json
    import shutil

    for cells in (4, 33, "8"):
        folder = tmp_path / f"bad-{cells}"
        shutil.copytree(mapped, folder)
        meta = json.loads((folder / "meta.json").read_text())
        meta["net"]["sight"]["map_cells"] = cells
        (folder / "meta.json").write_text(json.dumps(meta))
        # Resealed, as a forger would: the range check behind the manifest answers.
        reseal(folder)
        with pytest.raises(t2e.torch_policy.PolicyError, match="net.sight.map_cells"):
            t2e.load_policy(folder)
