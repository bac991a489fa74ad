"""Benchmark of ``sweep`` (the sweep target of issue 12), from one sitting.

Eight configurations (:data:`GRID`: ``noise_floor`` x ``regularizer`` x
``likelihood``, the hand observed) swept over every leave-one-out fold of a
data set, three times, each run from fresh worker processes into a fresh folder:

* ``sweep_1_worker_s``: one local worker process;
* ``sweep_2_workers_s``: ``workers`` local worker processes;
* ``sweep_dask_s``: a Dask ``LocalCluster`` of ``workers`` single-threaded
  processes (``--scheduler local``), if Dask is installed.

Each figure is the wall time of :func:`~sandbox.eval.sweep.run_sweep`, starting
and stopping its workers included; the trials are loaded once before
(``load_s``). Also reported: ``speedup`` (1 worker / ``workers``; target >=
1.7 on 2 cores), ``dask_vs_processes`` (Dask / processes; target <= 1.15),
``identical`` (the three runs stored the same results, timings aside), the
machine's core count and the number of folds. BLAS runs one thread per process.

Run ``python -m sandbox.bench.sweep --data ../shared/data/birl-handover-20180329 --json``;
``--n-per-task N`` keeps N trials per task for a quick run.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

from sandbox.bench import print_result, restart_single_threaded

#: The eight configurations swept.
GRID = {"noise_floor": [0.01, 0.02], "regularizer": [0.001, 0.01],
        "likelihood": ["joint", "marginal"]}
TARGETS = {"speedup": ">= 1.7", "dask_vs_processes": "<= 1.15"}
OBSERVE = ("hand",)


def _timed_sweep(trials, points, out: Path, workers: int, scheduler: str | None) -> float:
    from sandbox.eval.executors import open_executor
    from sandbox.eval.loocv import EvalConfig
    from sandbox.eval.sweep import run_sweep

    start = time.perf_counter()
    with open_executor(workers, scheduler) as executor:
        summary = run_sweep(executor, trials, points, out, base=EvalConfig(observe=OBSERVE),
                            log=lambda _: None)
    if summary["failed"]:
        raise RuntimeError(f"{len(summary['failed'])} configurations failed: "
                           f"{summary['failed'][0]['error']}")
    return time.perf_counter() - start


def _has_dask() -> bool:
    try:
        import distributed  # noqa: F401
    except ImportError:
        return False
    return True


def run_sweep_benchmark(data: str, *, n_per_task: int | None = None, workers: int = 2,
                        dask: bool = True, grid: dict | None = None,
                        log=lambda _: None) -> dict:
    """The figures of the module docstring, as a dict.

    Parameters
    ----------
    data : str
        A recorded set's folder or ``synthetic:NAME``.
    n_per_task : int, optional
        Trials per task (all if None): fewer folds for a quick run.
    workers : int
        Worker processes of the parallel runs.
    dask : bool
        Also time the Dask run (skipped if Dask is not installed).
    grid : dict, optional
        Another grid (lists of values) than :data:`GRID`.
    log : callable
        Receives a line as each run ends.
    """
    from sandbox.eval.datasets import load_pair
    from sandbox.eval.grid import parse_grid
    from sandbox.eval.sweep import stored_results

    points = parse_grid(GRID if grid is None else grid)
    start = time.perf_counter()
    train, test, _ = load_pair(data, n_per_task=n_per_task, observe=OBSERVE)
    out = {"cores": os.cpu_count(), "blas_threads": os.environ.get("OPENBLAS_NUM_THREADS"),
           "data": str(data), "configurations": len(points), "folds": len(train),
           "workers": workers, "load_s": round(time.perf_counter() - start, 2)}
    runs = {"sweep_1_worker_s": (1, None), "sweep_2_workers_s": (workers, None)}
    if dask and _has_dask():
        runs["sweep_dask_s"] = (workers, "local")
    stored = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, (n, scheduler) in runs.items():
            out[name] = round(_timed_sweep({OBSERVE: (train, test)}, points, Path(tmp) / name,
                                           n, scheduler), 2)
            stored[name] = stored_results(Path(tmp) / name)
            log(f"{name}: {out[name]} s")
    out["speedup"] = round(out["sweep_1_worker_s"] / out["sweep_2_workers_s"], 3)
    if "sweep_dask_s" in out:
        out["dask_vs_processes"] = round(out["sweep_dask_s"] / out["sweep_2_workers_s"], 3)
    results = list(stored.values())
    out["identical"] = len(results[0]) == len(points) and all(r == results[0] for r in results)
    out["targets"] = TARGETS
    return out


def main(argv=None) -> int:
    """``python -m sandbox.bench.sweep``: print the figures (one JSON object with ``--json``)."""
    parser = argparse.ArgumentParser(prog="python -m sandbox.bench.sweep",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("--data", required=True, help="a folder or synthetic:NAME")
    parser.add_argument("--n-per-task", type=int, default=None,
                        help="trials per task (default all): fewer folds, a quicker run")
    parser.add_argument("--workers", type=int, default=2, help="workers of the parallel runs")
    parser.add_argument("--no-dask", action="store_true", help="skip the Dask run")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    if argv is None:
        restart_single_threaded("sandbox.bench.sweep")
    result = run_sweep_benchmark(args.data, n_per_task=args.n_per_task, workers=args.workers,
                                 dask=not args.no_dask,
                                 log=lambda line: print(line, file=sys.stderr, flush=True))
    print_result(result, args.json, 24)
    return 0


if __name__ == "__main__":
    sys.exit(main())
