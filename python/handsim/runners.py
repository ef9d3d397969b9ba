"""Where sweeps run their jobs: this process, local worker processes, or a Ray cluster (``--ray [ADDRESS]``).

A runner has one method, ``map(fn, jobs) -> list``: ``fn(job)`` for every job, results in job order. Every job
of the sweeps is a pure function of its arguments (a trial's outcome depends only on its seed and condition),
so the runner decides where the work happens, never what comes out: the same jobs give the same results on
every runner. ``fn`` must be a module-level function (it is pickled to other processes and machines).
"""
from __future__ import annotations

import os


class LocalRunner:
    """In this process (workers=1) or in `workers` forked processes on this machine."""

    def __init__(self, workers: int = 1):
        if int(workers) < 1:
            raise ValueError(f"workers: expected >= 1, got {workers!r}")
        self.workers = int(workers)

    def map(self, fn, jobs):
        jobs = list(jobs)
        if self.workers > 1 and len(jobs) > 1:
            import multiprocessing as mp
            with mp.get_context("fork").Pool(min(self.workers, len(jobs))) as pool:
                return pool.map(fn, jobs, chunksize=1)
        return [fn(j) for j in jobs]

    def cores(self) -> int:
        return min(self.workers, os.cpu_count() or 1)

    def describe(self) -> str:
        return f"local, {self.workers} process(es)"


class RayRunner:
    """Jobs as Ray tasks: on a local Ray started here (address None, the default of ``--ray``) or on the
    cluster at `address` ("ray://host:10001", "auto"). Needs ``pip install ray`` (the ``bench`` extra)."""

    def __init__(self, address: str | None = None, num_cpus: int | None = None):
        try:
            import ray
        except ImportError as e:
            raise RuntimeError("--ray needs Ray: pip install 'ray>=2.9' (or the handsim[bench] extra)") from e
        self.ray = ray
        self.address = address
        if not ray.is_initialized():
            kwargs = {"ignore_reinit_error": True, "log_to_driver": False, "include_dashboard": False}
            if address:
                kwargs["address"] = address
            elif num_cpus:
                kwargs["num_cpus"] = int(num_cpus)
            ray.init(**kwargs)

    def map(self, fn, jobs):
        remote = self.ray.remote(num_cpus=1)(fn)
        return self.ray.get([remote.remote(j) for j in jobs])

    def cores(self) -> int:
        return int(self.ray.cluster_resources().get("CPU", 1))

    def describe(self) -> str:
        return f"Ray at {self.address or 'a local Ray'} ({self.cores()} CPU)"


def make_runner(ray=False, workers: int = 1):
    """The runner of a command line: `ray` is False (local, `workers` processes), None or "" (a local Ray) or an
    address (a Ray cluster)."""
    if ray is False:
        return LocalRunner(workers)
    return RayRunner(ray or None, num_cpus=workers if not ray else None)
