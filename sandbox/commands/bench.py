"""``python -m sandbox bench``: speed benchmarks (medians and ratios from one run)."""

from __future__ import annotations

from sandbox.commands import _types

NAME = "bench"
HELP = ("measure the speed of the predictor update (and of the environments, if present); "
        "about a minute or two, its stages counted by a progress bar on stderr")


def add_arguments(parser) -> None:
    """Add the ``bench`` command's options to ``parser``."""
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--repeats", type=_types.integer(1, 1_000_000), default=200,
                        help="repetitions per timed case, 1 to 1e6 (default 200)")
    parser.add_argument("--seed", type=_types.SEED, default=0, help="seed of the reference data")
    parser.add_argument("--methods", action="store_true",
                        help="also time the update of every method of 'compare' (dynamic, "
                             "static, bip, ebip, dtw, nearest; sandbox.bench.methods)")
    parser.add_argument("--skip-env", action="store_true",
                        help="skip the environment benchmarks")
    parser.add_argument("--skip-vector", action="store_true",
                        help="skip the vector-environment benchmark (gym.make_vec, N = 1, 2, 4)")
    parser.add_argument("--no-progress", action="store_true",
                        help="no progress bar on stderr")


def run(args) -> int:
    """Run ``python -m sandbox bench`` with the parsed ``args``; return the exit status."""
    from sandbox.bench import print_result, restart_single_threaded

    restart_single_threaded("sandbox")
    from sandbox.eval.progress import bar

    result = {"blas_threads": 1}
    stages = _stages(args)
    with bar(len(stages), "bench", not args.no_progress, unit="stage") as shown:
        for name, measure in stages:
            shown.set_postfix_str(name)
            result.update(measure())
            shown.update()
    print_result(result, args.json, 36)
    return 0


def _stages(args) -> list:
    """(name, function returning figures) of every benchmark this run measures."""
    from sandbox.bench.cases import run_case_benchmarks
    from sandbox.bench.core import run_core_benchmarks

    stages = [("predictor update",
               lambda: run_core_benchmarks(repeats=args.repeats, seed=args.seed)),
              ("many tasks and demos",
               lambda: run_case_benchmarks(repeats=args.repeats, seed=args.seed))]
    if getattr(args, "methods", False):
        from sandbox.bench.methods import run_method_benchmarks

        stages.append(("methods", lambda: run_method_benchmarks(seed=args.seed)))
    if args.skip_env:
        return stages
    try:
        from sandbox.bench.env import run_env_benchmarks, run_vector_benchmarks
    except ImportError:       # the environments' packages are missing: core figures only
        return stages
    stages.append(("environments", run_env_benchmarks))
    if not args.skip_vector:
        stages.append(("vector environments", run_vector_benchmarks))
    return stages
