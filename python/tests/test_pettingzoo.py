"""PettingZoo's own tests of a parallel env, run as they are."""

from pettingzoo.test import parallel_api_test, parallel_seed_test, render_test
from pettingzoo.utils.conversions import parallel_to_aec

import t2e


def make():
    return t2e.parallel_env(maps="shipped", num_captors=3, episode_length=60)


def test_parallel_api():
    parallel_api_test(make(), num_cycles=300)


def test_parallel_seed():
    parallel_seed_test(make)


def test_render():
    # render_test plays an AEC env, so the parallel env goes through
    # PettingZoo's own conversion. It builds one env with "human" only to
    # read the metadata's render modes ("rgb_array" here); that one is
    # made without rendering.
    def make_rendered(render_mode=None):
        mode = None if render_mode == "human" else render_mode
        return parallel_to_aec(t2e.parallel_env(maps="shipped", episode_length=60, render_mode=mode))

    render_test(make_rendered)
