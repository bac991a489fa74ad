"""``python -m sandbox tune``: pick the core's open defaults by leave-one-out on a dataset."""

from __future__ import annotations

from sandbox.commands import _executor, _observation, _types

NAME = "tune"
HELP = ("cross-validate likelihood, window mode, regulariser, noise floors, motion end and "
        "basis size")


def add_arguments(parser) -> None:
    parser.add_argument("--data", required=True, help="a folder in the shared layout or "
                                                      "synthetic:NAME")
    parser.add_argument("--window", type=_types.SECONDS, default=0.2,
                        help="dynamic window scored (s), in (0, 60]")
    _observation.add_arguments(parser)
    _executor.add_arguments(parser)
    parser.add_argument("--seed", type=_types.SEED, default=0, help="seed of synthetic data")
    parser.add_argument("--out", type=_types.output_file, default=None,
                        help="write the table (Markdown) here too")
    parser.add_argument("--json", type=_types.output_file, default=None,
                        help="write all rows and the choice as JSON")


def run(args) -> int:
    import json
    from pathlib import Path

    from sandbox.eval.datasets import load_pair
    from sandbox.eval.tune import HEADER, grid_for, table, tune

    spec = _observation.data_spec(args)
    observe = _observation.observe(args, spec)
    train, test, _ = load_pair(args.data, seed=args.seed, spec=spec, observe=observe)
    print("| " + " | ".join(HEADER) + " |")
    from sandbox.eval.loocv import EvalConfig

    grid = grid_for(spec.observed(observe))
    best, rows = tune(train, test, base=EvalConfig(observe=observe), window=args.window,
                      grid=grid, **_executor.options(args))
    chosen = {k: getattr(best, k) for k in grid}
    print(f"\nchosen: {chosen}")
    if args.out:
        Path(args.out).write_text(table(rows) + f"\nchosen: {chosen}\n")
    if args.json:
        Path(args.json).write_text(json.dumps({"rows": rows, "chosen": chosen}, indent=1))
    return 0
