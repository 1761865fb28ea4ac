"""Python and Rust give the same episodes for the same seed: the Rust
evaluation (`t2e-league eval`) records each episode's seed, map, length and
outcome, and the Python env with the same policies replays them exactly."""

import csv
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import t2e

ROOT = Path(__file__).resolve().parents[2]


def binary() -> Path:
    path = Path(os.environ.get("T2E_BIN", ROOT / "target" / "release" / "t2e-league"))
    if not path.is_file():
        pytest.fail(f"{path} is missing: build it first (cargo build --release)")
    return path


@pytest.mark.parametrize("captors, target", [("heuristic", "heuristic"), ("greedy:4", "heuristic")])
def test_the_rust_evaluations_episodes_replay_in_python(tmp_path, captors, target):
    out = tmp_path / "eval"
    subprocess.run(
        [str(binary()), "eval", "--captors", captors, "--target", target, "--maps", "shipped",
         "--k", "3", "--speed-ratio", "1.0", "--episodes", "4", "--seed", "7", "--out", str(out)],
        check=True, capture_output=True, cwd=ROOT,
    )
    rows = [row for path in sorted(out.rglob("episodes.csv")) for row in csv.DictReader(open(path))]
    assert len(rows) == 4
    env = t2e.parallel_env(maps="shipped", num_captors=3, episode_length=500, asz_info=False)
    play_captors = t2e.ScriptedPolicy(captors, "captors")
    play_target = t2e.ScriptedPolicy(target, "target")
    for row in rows:
        _, infos = env.reset(seed=int(row["seed"]))
        assert env.map_name == row["map"]
        steps, captured = 0, False
        while env.agents:
            actions = {**play_captors(env), **play_target(env)}
            _, _, terms, _, infos = env.step(actions)
            steps += 1
            captured = infos["target"]["captured"]
        assert (steps, captured) == (int(row["steps"]), row["captured"] == "true"), row


def test_asz_area_of_positions_equals_the_envs_own():
    env = t2e.parallel_env(maps="shipped", num_captors=3, episode_length=50)
    env.reset(seed=2)
    poses = env._env.poses
    captors = [(x, y) for x, y, _ in poses[:3]]
    target = poses[3][:2]
    assert t2e.asz_area(env._env, captors, target) == pytest.approx(env.asz_area(), abs=0)
    # Captors closer to the target leave it less.
    near = [(target[0] + dx, target[1] + dy) for dx, dy in [(0.6, 0), (-0.6, 0), (0, 0.6)]]
    free_near = t2e.asz_area(env._env, near, target)
    assert free_near < env.asz_area()
    with pytest.raises(ValueError, match="captors"):
        t2e.asz_area(env._env, [(float("nan"), 0.0)], target)


def test_the_vector_env_steps_worlds_with_auto_reset_as_single_envs_do():
    n = 3
    venv = t2e.vector_env(n, maps="shipped", episode_length=20, seed=5)
    vectors, patches = venv.reset()
    assert vectors.shape == (n, 4, 20) and vectors.dtype == np.float32
    assert patches.shape == (n, 4, 48, 48) and patches.dtype == np.uint8
    rng = np.random.default_rng(0)
    ended = np.zeros(n, dtype=int)
    for _ in range(45):
        actions = rng.integers(t2e.ACTIONS, size=(n, 4), dtype=np.int64)
        vectors, patches, rewards, terminated, truncated = venv.step(actions)
        assert rewards.shape == (n, 4)
        ended += terminated | truncated
    # 45 steps of 20-step episodes: every world has started over at least twice.
    assert (ended >= 2).all(), ended
    with pytest.raises(ValueError, match="actions"):
        venv.step(np.zeros((n, 3), dtype=np.int64))
    with pytest.raises(ValueError, match="actions"):
        venv.step(np.full((n, 4), 7, dtype=np.int64))
    with pytest.raises(ValueError, match="num_envs"):
        t2e.vector_env(0)
