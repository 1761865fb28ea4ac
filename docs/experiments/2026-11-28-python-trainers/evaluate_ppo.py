"""Plays a `python/examples/ppo_captors.py` agent (its agent.pt) greedily on
the starts `sb3_captors.py` tests on: the same classes, seeds and episode
length, so each episode is paired with the SB3 policy's. Writes eval.csv
and episodes.csv beside agent.pt in sb3_captors's columns.

    python evaluate_ppo.py runs/py-ppo-s0 [--episodes 100]
"""

import argparse
import csv
import importlib.util
import sys
import time
from pathlib import Path

import numpy as np
import torch

import t2e

EXAMPLES = Path(__file__).resolve().parents[3] / "python" / "examples"


def load(name):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("run")
    parser.add_argument("--episodes", type=int, default=100)
    cli = parser.parse_args()
    ppo, sb3 = load("ppo_captors"), load("sb3_captors")
    args = sb3.Args(eval_episodes=cli.episodes)
    torch.set_num_threads(1)
    pool = ppo.Args().pool
    env0 = t2e.parallel_env(maps="shipped", episode_length=1)
    agent = ppo.Agent(env0._env.vector_len, 48 // pool, ppo.Args().hidden)
    agent.load_state_dict(torch.load(Path(cli.run) / "agent.pt"))
    agent.eval()
    rows, episodes = [], []
    for label, maps, protocol in (("test", args.eval_maps, "test"), ("train", args.maps, "held-out")):
        for i, cls in enumerate(maps.split(",")):
            t0 = time.perf_counter()
            env = t2e.parallel_env(maps=cls, protocol=protocol, episode_length=args.eval_episode_length, target="heuristic")
            captured, steps = 0, 0
            base = sb3.eval_seed_base(label, i)
            for e in range(args.eval_episodes):
                observations, _ = env.reset(seed=base + e)
                start = steps
                while env.agents:
                    agents = env.agents
                    patches = np.stack([observations[a]["patch"] for a in agents])
                    vectors = torch.from_numpy(np.stack([observations[a]["vector"] for a in agents]))
                    with torch.no_grad():
                        logits, _ = agent(ppo.pool(patches, pool), vectors)
                    observations, _, terminations, _, _ = env.step(dict(zip(agents, logits.argmax(-1).tolist())))
                    steps += 1
                captured += any(terminations.values())
                episodes.append([label, cls, base + e, int(any(terminations.values())), steps - start])
            n = args.eval_episodes
            lo, hi = sb3.wilson(captured, n)
            rows.append([label, cls, n, captured, f"{100 * captured / n:.1f}", f"{lo:.1f}", f"{hi:.1f}", f"{steps / n:.0f}", f"{time.perf_counter() - t0:.0f}"])
            print(f"{label} {cls}: captured {captured}/{n} = {100 * captured / n:.1f}% [{lo:.1f}, {hi:.1f}]")
    with open(Path(cli.run) / "eval.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["maps", "class", "episodes", "captured", "captured_pct", "wilson_lo", "wilson_hi", "mean_steps", "seconds"])
        w.writerows(rows)
    with open(Path(cli.run) / "episodes.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["maps", "class", "seed", "captured", "steps"])
        w.writerows(episodes)


if __name__ == "__main__":
    main()
