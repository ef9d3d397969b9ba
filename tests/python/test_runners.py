"""Sweeps on other runners (issue 25): the same jobs give the same trials, seed for seed, on every runner."""
import concurrent.futures
import importlib.util

import pytest

from handsim import experiments as X
from handsim.runners import LocalRunner, make_runner

SWEEP = dict(trials=2, methods=("exact",), thresholds=(-0.7,), cells=(("open", 1), ("close", 1)))


class PoolRunner:
    """A stand-in for a cluster: the runner interface (map) over a process pool of another kind."""

    def map(self, fn, jobs):
        with concurrent.futures.ProcessPoolExecutor(max_workers=2) as pool:
            return list(pool.map(fn, jobs))


def _outcomes(results):
    return [(r.seed, r.method, r.threshold, r.task, r.hands, r.success, r.time_s, r.final_angle, r.grasp_begins,
             r.drop, r.knocked) for r in results]


@pytest.fixture(scope="module")
def local():
    return _outcomes(X.run_all(runner=LocalRunner(1), **SWEEP))


def test_a_runner_of_another_kind_gives_the_same_trials(local):
    assert _outcomes(X.run_all(runner=PoolRunner(), **SWEEP)) == local
    assert _outcomes(X.run_all(runner=LocalRunner(2), **SWEEP)) == local


def test_bad_runner_arguments_name_themselves():
    with pytest.raises(ValueError, match="workers"):
        LocalRunner(0)


@pytest.mark.skipif(importlib.util.find_spec("ray") is None,
                    reason="Ray is not installed (pip install 'ray>=2.9', the handsim[bench] extra)")
def test_a_local_ray_gives_the_same_trials(local):
    runner = make_runner("", workers=2)  # --ray without an address: a local Ray
    try:
        assert _outcomes(X.run_all(runner=runner, **SWEEP)) == local
    finally:
        runner.ray.shutdown()
