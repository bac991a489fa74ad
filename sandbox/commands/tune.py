"""``python -m sandbox tune``: pick the core's open defaults by leave-one-out on a dataset.

``--out settings.yaml`` writes the chosen settings (and ``observe``) as a
settings file that ``fit``, ``evaluate``, ``play`` and ``sweep`` take with
``--config settings.yaml`` (see ``sandbox/commands/_settings.py``);
``--markdown`` writes the table of every run, ``--json`` the rows and the choice.
"""

from __future__ import annotations

from sandbox.commands import _executor, _observation, _outputs, _settings, _skipped, _types

NAME = "tune"
HELP = ("cross-validate likelihood, window mode, regulariser, noise floors, motion end and "
        "basis size: one leave-one-out per grid value (the grid has about 20), so it takes "
        "about 20 evaluate runs; a progress bar on stderr counts the trials and gives an ETA")
SETTINGS_SUFFIXES = (".yaml", ".yml", ".json")


def add_arguments(parser) -> None:
    """Add the ``tune`` command's options to ``parser``."""
    parser.add_argument("--data", required=True, help="a folder in the shared layout or "
                                                      "synthetic:NAME")
    parser.add_argument("--window", type=_types.SECONDS, default=0.2,
                        help="dynamic window scored (s), in (0, 60] (default 0.2)")
    _observation.add_arguments(parser)
    _observation.add_cache_argument(parser)
    _executor.add_arguments(parser)
    parser.add_argument("--seed", type=_types.SEED, default=0, help="seed of synthetic data")
    parser.add_argument("--tasks", default=None, help="comma-separated subset of tasks")
    parser.add_argument("--n-per-task", type=_types.PER_TASK, default=None,
                        help="trials per task (synthetic: generated; folder: first N)")
    parser.add_argument("--out", type=_types.output_file, default=None, metavar="SETTINGS",
                        help="write the chosen settings here (.yaml or .json), for --config "
                             "of fit, evaluate, play and sweep")
    parser.add_argument("--markdown", type=_types.output_file, default=None, metavar="FILE",
                        help="write the table of every run (Markdown) here")
    parser.add_argument("--json", type=_types.output_file, default=None,
                        help="write all rows and the choice as JSON")
    _outputs.add_force(parser, "--out, --markdown and --json files")
    _skipped.add_argument(parser)
    parser.add_argument("--no-progress", action="store_true",
                        help="no progress bar on stderr")


def _check(args) -> None:
    from pathlib import Path

    if args.out is not None and Path(args.out).suffix.lower() not in SETTINGS_SUFFIXES:
        raise ValueError(f"--out: expected a settings file ending in .yaml, .yml or .json "
                         f"(the Markdown table is --markdown), got {args.out!r}")
    _outputs.check_new([("--out", args.out), ("--markdown", args.markdown),
                        ("--json", args.json)], args.force)


def run(args) -> int:
    """Run ``python -m sandbox tune`` with the parsed ``args``; return the exit status."""
    import json

    from sandbox.eval.datasets import load_pair
    from sandbox.eval.loocv import EvalConfig
    from sandbox.eval.tune import HEADER, grid_for, table, tune

    _check(args)
    spec = _observation.data_spec(args)
    observe = _observation.observe(args, spec)
    train, test, skipped = load_pair(args.data, seed=args.seed, spec=spec, observe=observe,
                                     tasks=_observation.split(args.tasks),
                                     n_per_task=args.n_per_task, cache=_observation.cache(args))
    _skipped.report(skipped, args.verbose, len(train))
    if not train:
        raise _skipped.no_usable(args.data, skipped, verbose=args.verbose)
    print("| " + " | ".join(HEADER) + " |")
    grid = grid_for(spec.observed(observe))
    best, rows = tune(train, test, base=EvalConfig(observe=observe), window=args.window,
                      grid=grid, progress=not args.no_progress, **_executor.options(args))
    chosen = {k: getattr(best, k) for k in grid}
    print(f"\nchosen: {chosen}")
    if args.out:
        _settings.to_file(chosen, observe, args.out,
                          f"settings chosen by: python -m sandbox tune --data {args.data} "
                          f"(window {args.window:g} s)\nuse: --config {args.out} on fit, "
                          "evaluate, play or sweep")
        print(f"settings: {args.out}")
    if args.markdown:
        _outputs.write_text(args.markdown, table(rows) + f"\nchosen: {chosen}\n")
    if args.json:
        _outputs.write_text(args.json, json.dumps({"rows": rows, "chosen": chosen}, indent=1))
    return 0
