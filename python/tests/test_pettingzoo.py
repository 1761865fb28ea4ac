"""PettingZoo's own tests of a parallel env, run as they are."""

from pettingzoo.test import parallel_api_test, parallel_seed_test

import t2e


def make():
    return t2e.parallel_env(maps="shipped", num_captors=3, episode_length=60)


def test_parallel_api():
    parallel_api_test(make(), num_cycles=300)


def test_parallel_api_with_every_observation_option():
    for observation in ("egocentric", "flat", "image"):
        parallel_api_test(t2e.parallel_env(maps="shipped", episode_length=60, observation=observation), num_cycles=100)
    parallel_api_test(t2e.parallel_env(maps="shipped", episode_length=60, target="heuristic", observation="flat"), num_cycles=100)


def test_parallel_seed():
    parallel_seed_test(make)
