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
