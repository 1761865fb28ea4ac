"""Captors learn to trap the rule-based target with PPO, CleanRL-style:
one file, every hyperparameter in `Args`, the algorithm top to bottom.

The three captors share one policy and one value function, each reading
its own robot's observation (IPPO). The worlds step in Rust
(`t2e.vector_env`), the rule-based target plays there too, and the
network is PyTorch. Each iteration prints and appends to the curve CSV:
env steps, wall-clock, the captors' mean episode return and how often
episodes end in a capture.

    python python/examples/ppo_captors.py --iterations 200 --out runs/py-ppo
"""

from __future__ import annotations

import argparse
import csv
import os
import time
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np
import torch
from torch import nn

import t2e


@dataclass
class Args:
    maps: str = "shipped"
    num_captors: int = 3
    episode_length: int = 200
    num_envs: int = 16
    """Worlds stepped together."""
    rollout_steps: int = 64
    iterations: int = 200
    lr: float = 3e-4
    gamma: float = 0.99
    gae_lambda: float = 0.95
    epochs: int = 4
    minibatches: int = 4
    clip: float = 0.2
    entropy_coef: float = 0.01
    value_coef: float = 0.5
    max_grad_norm: float = 0.5
    pool: int = 4
    """The 48 x 48 patch is max-pooled to 12 x 12 before the CNN."""
    hidden: int = 64
    reward_scale: float = 0.01
    """Rewards are learned from times this (a capture pays 200); the curve
    reports them unscaled."""
    seed: int = 0
    threads: int = 1
    out: str = "runs/py-ppo"


class Encoder(nn.Module):
    """A small CNN over the pooled obstacle patch and an MLP over the
    vector turned into the robot's own frame (the egocentric features of
    t2e-league's networks), concatenated."""

    def __init__(self, vector_len: int, side: int, hidden: int):
        super().__init__()
        width = 6 + 9 * ((vector_len - 5) // 5)
        self.patch = nn.Sequential(
            nn.Conv2d(1, 8, 3, stride=2), nn.ReLU(), nn.Flatten(),
            nn.Linear(8 * ((side - 3) // 2 + 1) ** 2, hidden), nn.ReLU(),
        )
        self.vector = nn.Sequential(nn.LayerNorm(width), nn.Linear(width, hidden), nn.ReLU())
        self.merge = nn.Sequential(nn.Linear(2 * hidden, hidden), nn.ReLU())

    def forward(self, patches, vectors):
        v = egocentric(vectors)
        return self.merge(torch.cat([self.patch(patches), self.vector(v)], -1))


def egocentric(vectors):
    from t2e.torch_policy import _vector_features

    return _vector_features(vectors, 1, "egocentric")


class Agent(nn.Module):
    """Actor and critic, each with its own encoder (CleanRL's layout): the
    critic's large value errors do not pull on the policy's features."""

    def __init__(self, vector_len: int, side: int, hidden: int):
        super().__init__()
        self.actor = nn.Sequential(Encoder(vector_len, side, hidden))
        self.critic = nn.Sequential(Encoder(vector_len, side, hidden))
        self.policy = nn.Linear(hidden, t2e.ACTIONS)
        self.value = nn.Linear(hidden, 1)
        nn.init.uniform_(self.policy.weight, -0.01, 0.01)

    def forward(self, patches, vectors):
        logits = self.policy(self.actor[0](patches, vectors))
        return logits, self.value(self.critic[0](patches, vectors)).squeeze(-1)


def pool(patches: np.ndarray, k: int) -> torch.Tensor:
    """[..., 48, 48] uint8 -> [..., 1, 48/k, 48/k] float: an obstacle
    anywhere in a k x k block marks the pooled cell."""
    *lead, h, w = patches.shape
    p = patches.reshape(*lead, h // k, k, w // k, k).max(axis=(-3, -1))
    return torch.from_numpy(p).float().unsqueeze(-3)


def main(args: Args) -> Path:
    torch.manual_seed(args.seed)
    torch.set_num_threads(args.threads)
    rng = np.random.default_rng(args.seed)
    k = args.num_captors
    venv = t2e.vector_env(
        args.num_envs, maps=args.maps, num_captors=k, episode_length=args.episode_length,
        seed=args.seed, target="heuristic",
    )
    n, agents = args.num_envs, k + 1
    vectors, patches = venv.reset()
    agent = Agent(venv.vector_len, 48 // args.pool, args.hidden)
    optimizer = torch.optim.Adam(agent.parameters(), lr=args.lr, eps=1e-5)

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    curve = out / "curve.csv"
    with open(curve, "w", newline="") as f:
        csv.writer(f).writerow(["iteration", "env_steps", "seconds", "episodes", "mean_return", "capture_rate", "loss"])

    T, rows = args.rollout_steps, n * k
    episode_return = np.zeros(n)
    start, env_steps = time.time(), 0
    for iteration in range(1, args.iterations + 1):
        obs_p = torch.zeros(T, rows, 1, 48 // args.pool, 48 // args.pool)
        obs_v = torch.zeros(T, rows, venv.vector_len)
        actions = torch.zeros(T, rows, dtype=torch.long)
        logprobs = torch.zeros(T, rows)
        values = torch.zeros(T, rows)
        rewards = torch.zeros(T, rows)
        dones = torch.zeros(T, rows)
        finished_returns, captures = [], 0

        # Rollout: every world steps together; the target's actions are
        # the Rust rule-based target's (the zeros given for it are ignored).
        for t in range(T):
            p = pool(patches[:, :k], args.pool).reshape(rows, 1, 48 // args.pool, 48 // args.pool)
            v = torch.from_numpy(vectors[:, :k].reshape(rows, -1).copy())
            with torch.no_grad():
                logits, value = agent(p, v)
            dist = torch.distributions.Categorical(logits=logits)
            a = dist.sample()
            obs_p[t], obs_v[t], actions[t], logprobs[t], values[t] = p, v, a, dist.log_prob(a), value
            step_actions = np.zeros((n, agents), dtype=np.int64)
            step_actions[:, :k] = a.numpy().reshape(n, k)
            vectors, patches, r, terminated, truncated = venv.step(step_actions)
            rewards[t] = torch.from_numpy(r[:, :k].reshape(rows).copy()) * args.reward_scale
            ended = terminated | truncated
            # A capture ends the game; a truncation is cut short, but this
            # sketch does not bootstrap there (see docs/algorithms/mappo.md).
            dones[t] = torch.from_numpy(np.repeat(ended, k).astype(np.float32))
            episode_return += r[:, :k].mean(axis=1)
            for w in np.flatnonzero(ended):
                finished_returns.append(episode_return[w])
                captures += int(terminated[w])
                episode_return[w] = 0.0
        env_steps += T * n

        # GAE over the rollout, bootstrapped from the next state.
        with torch.no_grad():
            p = pool(patches[:, :k], args.pool).reshape(rows, 1, 48 // args.pool, 48 // args.pool)
            _, next_value = agent(p, torch.from_numpy(vectors[:, :k].reshape(rows, -1).copy()))
        advantages = torch.zeros(T, rows)
        gae = torch.zeros(rows)
        for t in reversed(range(T)):
            following = next_value if t == T - 1 else values[t + 1]
            alive = 1.0 - dones[t]
            delta = rewards[t] + args.gamma * following * alive - values[t]
            gae = delta + args.gamma * args.gae_lambda * alive * gae
            advantages[t] = gae
        returns = advantages + values

        # PPO update: clipped surrogate, value loss, entropy bonus.
        b = T * rows
        flat = lambda x: x.reshape(b, *x.shape[2:])  # noqa: E731
        bp, bv, ba, blp, badv, bret = map(flat, (obs_p, obs_v, actions, logprobs, advantages, returns))
        size = b // args.minibatches
        for _ in range(args.epochs):
            order = torch.from_numpy(rng.permutation(b))
            for s in range(0, b, size):
                mb = order[s : s + size]
                logits, value = agent(bp[mb], bv[mb])
                dist = torch.distributions.Categorical(logits=logits)
                ratio = (dist.log_prob(ba[mb]) - blp[mb]).exp()
                adv = (badv[mb] - badv[mb].mean()) / (badv[mb].std() + 1e-8)
                policy_loss = -torch.min(ratio * adv, ratio.clamp(1 - args.clip, 1 + args.clip) * adv).mean()
                value_loss = 0.5 * (value - bret[mb]).pow(2).mean()
                loss = policy_loss + args.value_coef * value_loss - args.entropy_coef * dist.entropy().mean()
                optimizer.zero_grad()
                loss.backward()
                nn.utils.clip_grad_norm_(agent.parameters(), args.max_grad_norm)
                optimizer.step()
        if not torch.isfinite(loss):
            raise RuntimeError(f"iteration {iteration}: the loss is {loss.item()}")

        episodes = len(finished_returns)
        mean_return = float(np.mean(finished_returns)) if episodes else float("nan")
        rate = captures / episodes if episodes else float("nan")
        seconds = time.time() - start
        with open(curve, "a", newline="") as f:
            csv.writer(f).writerow([iteration, env_steps, f"{seconds:.1f}", episodes, f"{mean_return:.2f}", f"{rate:.3f}", f"{loss.item():.4f}"])
        print(f"iteration {iteration}: {env_steps} env steps, {seconds:.0f} s, {episodes} episodes, "
              f"captors' return {mean_return:.1f}, captured {rate:.0%}")
    torch.save(agent.state_dict(), out / "agent.pt")
    return curve


def parse() -> Args:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    for f in fields(Args):
        parser.add_argument("--" + f.name.replace("_", "-"), type=type(f.default), default=f.default)
    return Args(**vars(parser.parse_args()))


if __name__ == "__main__":
    os.environ.setdefault("RAYON_NUM_THREADS", "1")
    main(parse())
