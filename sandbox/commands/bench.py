"""``python -m sandbox bench``: speed benchmarks (medians and ratios from one run)."""

from __future__ import annotations

import json
import os

from sandbox.commands import _types

NAME = "bench"
HELP = "measure the speed of the predictor update (and of the environments, if present)"


def add_arguments(parser) -> None:
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--repeats", type=_types.integer(1, 1_000_000), default=200,
                        help="repetitions per timed case, 1 to 1e6 (default 200)")
    parser.add_argument("--seed", type=_types.SEED, default=0, help="seed of the reference data")
    parser.add_argument("--skip-env", action="store_true",
                        help="skip the environment benchmarks")


def run(args) -> int:
    if args.repeats < 1:
        raise ValueError(f"--repeats: expected a positive integer, got {args.repeats}")
    threads = os.environ.get("OPENBLAS_NUM_THREADS")
    if threads != "1":
        _restart_single_threaded()
    from sandbox.bench.core import run_core_benchmarks

    result = {"blas_threads": 1}
    result.update(run_core_benchmarks(repeats=args.repeats, seed=args.seed))
    if not args.skip_env:
        try:
            from sandbox.bench.env import run_env_benchmarks
        except ImportError:
            run_env_benchmarks = None
        if run_env_benchmarks is not None:
            result.update(run_env_benchmarks())
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        for key, value in result.items():
            print(f"{key:36s} {value}")
    return 0


def _restart_single_threaded() -> None:
    """Re-exec this command with one BLAS thread (the limit is read at numpy import)."""
    import sys

    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    os.execve(sys.executable, [sys.executable, "-m", "sandbox", *sys.argv[1:]], env)
