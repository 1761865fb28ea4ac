"""The CleanRL-style example runs: a few iterations, a curve with finite
numbers, and episodes that end."""

import csv
import importlib.util
import math
import sys
from pathlib import Path

import pytest

pytest.importorskip("torch")

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "ppo_captors.py"


def test_the_ppo_example_trains_a_few_iterations(tmp_path):
    spec = importlib.util.spec_from_file_location("ppo_captors", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    args = module.Args(num_envs=4, rollout_steps=32, episode_length=40, iterations=3, out=str(tmp_path))
    curve = module.main(args)
    rows = list(csv.DictReader(open(curve)))
    assert [int(r["iteration"]) for r in rows] == [1, 2, 3]
    assert [int(r["env_steps"]) for r in rows] == [128, 256, 384]
    # 40-step episodes in 32-step rollouts of 4 worlds: episodes end.
    assert sum(int(r["episodes"]) for r in rows) >= 4
    assert all(math.isfinite(float(r["loss"])) for r in rows)
    assert (tmp_path / "agent.pt").is_file()


SB3_EXAMPLE = EXAMPLE.with_name("sb3_captors.py")


def test_the_stable_baselines3_example_trains_and_evaluates(tmp_path):
    for library in ("supersuit", "stable_baselines3"):
        pytest.importorskip(library)
    spec = importlib.util.spec_from_file_location("sb3_captors", SB3_EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    args = module.Args(
        num_envs=2, n_steps=64, batch_size=96, captor_steps=2 * 3 * 64 * 2, episode_length=50,
        eval_episodes=2, eval_episode_length=30, out=str(tmp_path),
    )
    module.main(args)
    curve = list(csv.DictReader(open(tmp_path / "curve.csv")))
    assert [int(r["captor_steps"]) for r in curve] == [384, 768]
    assert [int(r["env_steps"]) for r in curve] == [128, 256]
    # 50-step episodes, 128 env steps a rollout over 2 worlds: some end.
    assert sum(int(r["episodes"]) for r in curve) >= 4
    rows = list(csv.DictReader(open(tmp_path / "eval.csv")))
    assert [(r["maps"], r["class"]) for r in rows] == [("test", "small"), ("test", "medium"), ("test", "large"), ("train", "shipped")]
    assert all(int(r["episodes"]) == 2 and 0 <= int(r["captured"]) <= 2 for r in rows)
    assert all(0 < float(r["mean_steps"]) <= 30 for r in rows)
    assert (tmp_path / "model.zip").is_file()
    episodes = list(csv.DictReader(open(tmp_path / "episodes.csv")))
    assert len(episodes) == 8 and len({(e["class"], e["seed"]) for e in episodes}) == 8
