"""Steps per second of the environment from Python: one PettingZoo env
(dict in, dict out) with its defaults and with each option that costs
time, the raw single env (numpy in, numpy out) and the batched vector
env, on one thread (RAYON_NUM_THREADS=1 unless set). An agent-step is one
agent's observation, action and reward: a step of the env with K captors
and the target is K + 1 of them.

    RAYON_NUM_THREADS=1 python python/examples/speed.py [--seconds 5]
"""

import argparse
import os
import time

os.environ.setdefault("RAYON_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import t2e  # noqa: E402


def rate(step, seconds):
    n, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        n += step()
    return n / (time.perf_counter() - start)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--maps", default="shipped")
    parser.add_argument("--num-envs", type=int, default=64)
    args = parser.parse_args()
    rng = np.random.default_rng(0)

    settings = [
        ("defaults", {}),
        ("with the ASZ in infos", {"asz_info": True}),
        ('observation="egocentric"', {"observation": "egocentric"}),
        ('observation="flat"', {"observation": "flat"}),
        ('target="heuristic", observation="flat"', {"target": "heuristic", "observation": "flat"}),
    ]
    for label, kwargs in settings:
        env = t2e.parallel_env(maps=args.maps, episode_length=500, **kwargs)
        env.reset(seed=0)
        agents = len(env.possible_agents)

        def pz_step():
            if not env.agents:
                env.reset()
            env.step({a: int(rng.integers(5)) for a in env.agents})
            return 1

        steps = rate(pz_step, args.seconds)
        print(f"parallel_env, {label}: {steps:,.0f} steps/s, {agents * steps:,.0f} agent-steps/s")

    raw = t2e.Env(args.maps, 3, 1.0, "held-out", 500)
    raw.reset(0)
    actions = np.zeros(4, dtype=np.int64)

    def raw_step():
        *_, terminated, truncated, _ = raw.step(actions)
        if terminated or truncated:
            raw.reset(int(rng.integers(2**63)))
        return 1

    print(f"Env (numpy arrays): {rate(raw_step, args.seconds):,.0f} steps/s")

    venv = t2e.vector_env(args.num_envs, maps=args.maps, episode_length=500)
    venv.reset()
    batch = rng.integers(5, size=(args.num_envs, 4), dtype=np.int64)

    def vec_step():
        venv.step(batch)
        return args.num_envs

    print(
        f"vector_env({args.num_envs}), RAYON_NUM_THREADS={os.environ['RAYON_NUM_THREADS']}: "
        f"{rate(vec_step, args.seconds):,.0f} world-steps/s"
    )


if __name__ == "__main__":
    main()
