"""``python -m sandbox bench``: speed benchmarks (medians and ratios from one run)."""

from __future__ import annotations

from sandbox.commands import _types

NAME = "bench"
HELP = "measure the speed of the predictor update (and of the environments, if present)"


def add_arguments(parser) -> None:
    """Add the ``bench`` command's options to ``parser``."""
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--repeats", type=_types.integer(1, 1_000_000), default=200,
                        help="repetitions per timed case, 1 to 1e6 (default 200)")
    parser.add_argument("--seed", type=_types.SEED, default=0, help="seed of the reference data")
    parser.add_argument("--skip-env", action="store_true",
                        help="skip the environment benchmarks")
    parser.add_argument("--skip-vector", action="store_true",
                        help="skip the vector-environment benchmark (gym.make_vec, N = 1, 2, 4)")


def run(args) -> int:
    """Run ``python -m sandbox bench`` with the parsed ``args``; return the exit status."""
    from sandbox.bench import print_result, restart_single_threaded

    restart_single_threaded("sandbox")
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
            if not args.skip_vector:
                from sandbox.bench.env import run_vector_benchmarks

                result.update(run_vector_benchmarks())
    print_result(result, args.json, 36)
    return 0
