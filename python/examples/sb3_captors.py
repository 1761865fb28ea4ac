"""Captors learn to trap the rule-based target with Stable-Baselines3's PPO,
from the env as it is: `t2e.parallel_env` with the rule-based target
inside (`target="heuristic"`) and the flat observation (the egocentric
vector and the pooled patch in one float32 vector), turned into a vector
env by SuperSuit. The three captors share SB3's MLP policy, each reading
its own robot's observation.

Each rollout appends a line to `curve.csv` (captor steps, env steps,
wall-clock, episodes ended, the share that ended in a capture). At the end
the greedy policy plays fresh seeds on maps it never trained on (the
Gibson test maps by default) and on its own training maps, and writes
`eval.csv` with each class's capture rate and a 95% Wilson interval, and
`episodes.csv` with each episode's seed and outcome.

    RAYON_NUM_THREADS=1 python python/examples/sb3_captors.py --captor-steps 1000000 --out runs/sb3-captors
"""

from __future__ import annotations

import argparse
import csv
import math
import time
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np
import supersuit as ss
import torch
from stable_baselines3 import PPO
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.utils import set_random_seed
from stable_baselines3.common.vec_env import VecNormalize

import t2e


@dataclass
class Args:
    maps: str = "shipped"
    """The maps it trains on (the nine shipped generated maps)."""
    eval_maps: str = "small,medium,large"
    """The maps it is tested on: the Gibson test maps, never trained on."""
    num_captors: int = 3
    speed_ratio: float = 1.0
    episode_length: int = 200
    """Training episodes; the test plays the spec's 500 steps."""
    eval_episode_length: int = 500
    eval_episodes: int = 100
    """Per map class, each on a fresh seed."""
    num_envs: int = 8
    """Worlds stepped together (each gives num_captors rows to SB3)."""
    captor_steps: int = 1_000_000
    """The budget, counted as SB3 counts: one step of one captor."""
    patch_pool: int = 4
    """The 48 x 48 patch is max-pooled to 12 x 12."""
    n_steps: int = 128
    batch_size: int = 768
    n_epochs: int = 4
    learning_rate: float = 3e-4
    gamma: float = 0.99
    gae_lambda: float = 0.95
    ent_coef: float = 0.01
    hidden: int = 128
    seed: int = 0
    threads: int = 1
    out: str = "runs/sb3-captors"
    evaluate_only: bool = False
    """Skip training: test the model.zip already in `out`."""


class Curve(BaseCallback):
    """Appends one line per rollout: captor steps, env steps, wall-clock,
    episodes ended and how many of them in a capture."""

    def __init__(self, path: Path, agents: int):
        super().__init__()
        self.path, self.agents = path, agents
        self.start = time.perf_counter()
        self.ended = self.captured = 0
        with open(path, "w", newline="") as f:
            csv.writer(f).writerow(["captor_steps", "env_steps", "seconds", "episodes", "captured"])

    def _on_step(self) -> bool:
        # Every captor of a world sees the same end: count the first's.
        dones, infos = self.locals["dones"], self.locals["infos"]
        for i in range(0, len(dones), self.agents):
            if dones[i]:
                self.ended += 1
                self.captured += bool(infos[i]["captured"])
        return True

    def _on_rollout_end(self) -> None:
        with open(self.path, "a", newline="") as f:
            csv.writer(f).writerow(
                [self.num_timesteps, self.num_timesteps // self.agents, f"{time.perf_counter() - self.start:.1f}", self.ended, self.captured]
            )
        self.ended = self.captured = 0


def wilson(k: int, n: int) -> tuple[float, float]:
    if n == 0:
        return (0.0, 0.0)
    z, p = 1.96, k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return (100 * (centre - half), 100 * (centre + half))


def evaluate(model: PPO, args: Args, maps: str, protocol: str, seed_base: int) -> list[tuple[int, bool, int]]:
    """(seed, captured, steps) of `eval_episodes` greedy episodes on `maps`,
    on fixed seeds of their own (training draws its seeds at random from
    2**64), so another policy can be paired with these episodes."""
    env = t2e.parallel_env(
        maps=maps, protocol=protocol, num_captors=args.num_captors, speed_ratio=args.speed_ratio,
        episode_length=args.eval_episode_length, target="heuristic", observation="flat", patch_pool=args.patch_pool,
    )
    episodes = []
    for e in range(args.eval_episodes):
        observations, _ = env.reset(seed=seed_base + e)
        steps = 0
        while env.agents:
            batch = np.stack([observations[a] for a in env.agents])
            actions, _ = model.predict(batch, deterministic=True)
            observations, _, terminations, _, _ = env.step(dict(zip(env.agents, actions.tolist())))
            steps += 1
        episodes.append((seed_base + e, any(terminations.values()), steps))
    return episodes


def eval_seed_base(label: str, index: int) -> int:
    """The first evaluation seed of map class `index` of the test or the
    training maps."""
    return 2**63 + 1_000 * (index + 10 * (label == "train"))


def evaluate_all(model: PPO, args: Args, out: Path) -> None:
    """eval.csv (per class, with 95% Wilson intervals) and episodes.csv
    (per episode) on the test maps and the training maps."""
    rows, episodes = [], []
    for label, maps, protocol in (("test", args.eval_maps, "test"), ("train", args.maps, "held-out")):
        for i, cls in enumerate(maps.split(",")):
            t0 = time.perf_counter()
            played = evaluate(model, args, cls, protocol, eval_seed_base(label, i))
            k, n = sum(c for _, c, _ in played), len(played)
            lo, hi = wilson(k, n)
            mean_steps = sum(s for *_, s in played) / n
            rows.append([label, cls, n, k, f"{100 * k / n:.1f}", f"{lo:.1f}", f"{hi:.1f}", f"{mean_steps:.0f}", f"{time.perf_counter() - t0:.0f}"])
            episodes += [[label, cls, seed, int(c), steps] for seed, c, steps in played]
            print(f"{label} {cls}: captured {k}/{n} = {100 * k / n:.1f}% [{lo:.1f}, {hi:.1f}]")
    with open(out / "eval.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["maps", "class", "episodes", "captured", "captured_pct", "wilson_lo", "wilson_hi", "mean_steps", "seconds"])
        w.writerows(rows)
    with open(out / "episodes.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["maps", "class", "seed", "captured", "steps"])
        w.writerows(episodes)


def main(args: Args) -> Path:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    torch.set_num_threads(args.threads)
    set_random_seed(args.seed)
    if args.evaluate_only:
        evaluate_all(PPO.load(out / "model.zip", device="cpu"), args, out)
        return out
    env = t2e.parallel_env(
        maps=args.maps, num_captors=args.num_captors, speed_ratio=args.speed_ratio,
        episode_length=args.episode_length, target="heuristic", observation="flat", patch_pool=args.patch_pool,
    )
    venv = ss.concat_vec_envs_v1(ss.pettingzoo_env_to_vec_env_v1(env), args.num_envs, num_cpus=0, base_class="stable_baselines3")
    # Rewards run to +200 for a capture: SB3's running normalisation keeps
    # the value targets near one.
    venv = VecNormalize(venv, norm_obs=False, norm_reward=True, gamma=args.gamma)
    # SB3's PPO(seed=...) calls venv.seed(), which SuperSuit's vector env
    # lacks: the seeds go in through reset instead.
    venv.venv.venv.reset(seed=args.seed * 1_000_003)
    model = PPO(
        "MlpPolicy", venv, n_steps=args.n_steps, batch_size=args.batch_size, n_epochs=args.n_epochs,
        learning_rate=args.learning_rate, gamma=args.gamma, gae_lambda=args.gae_lambda, ent_coef=args.ent_coef,
        policy_kwargs=dict(net_arch=[args.hidden, args.hidden]), device="cpu", verbose=0,
    )
    start = time.perf_counter()
    model.learn(total_timesteps=args.captor_steps, callback=Curve(out / "curve.csv", args.num_captors))
    train_seconds = time.perf_counter() - start
    model.save(out / "model.zip")
    venv.close()

    evaluate_all(model, args, out)
    with open(out / "run.txt", "w") as f:
        f.write(f"train_seconds {train_seconds:.0f}\ncaptor_steps {model.num_timesteps}\n")
        for field in fields(Args):
            f.write(f"{field.name} {getattr(args, field.name)}\n")
    print(f"trained {model.num_timesteps} captor steps in {train_seconds:.0f} s; {out / 'curve.csv'}, {out / 'eval.csv'}, {out / 'episodes.csv'}")
    return out


def parse() -> Args:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    for field in fields(Args):
        flag = "--" + field.name.replace("_", "-")
        if isinstance(field.default, bool):
            parser.add_argument(flag, action=argparse.BooleanOptionalAction, default=field.default)
        else:
            parser.add_argument(flag, type=type(field.default), default=field.default)
    return Args(**vars(parser.parse_args()))


if __name__ == "__main__":
    main(parse())
