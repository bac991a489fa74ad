"""``python -m sandbox tune``: pick the core's open defaults by leave-one-out on a dataset."""

from __future__ import annotations

NAME = "tune"
HELP = "cross-validate likelihood, window mode, regulariser, noise scale and basis size"


def add_arguments(parser) -> None:
    parser.add_argument("--data", required=True, help="a folder in the shared layout or "
                                                      "synthetic:NAME")
    parser.add_argument("--window", type=float, default=0.2, help="dynamic window scored (s)")
    parser.add_argument("--workers", type=int, default=2, help="processes (default 2)")
    parser.add_argument("--seed", type=int, default=0, help="seed of synthetic data")
    parser.add_argument("--out", default=None, help="write the table (Markdown) here too")
    parser.add_argument("--json", default=None, help="write all rows and the choice as JSON")


def run(args) -> int:
    import json
    from pathlib import Path

    from sandbox.eval.datasets import load_pair
    from sandbox.eval.tune import HEADER, table, tune

    if args.window <= 0:
        raise ValueError(f"--window: expected a positive number of seconds, got {args.window}")
    train, test, _ = load_pair(args.data, seed=args.seed)
    print("| " + " | ".join(HEADER) + " |")
    best, rows = tune(train, test, window=args.window, workers=max(1, args.workers))
    chosen = {k: getattr(best, k) for k in ("noise_floor", "regularizer", "likelihood",
                                            "window_mode", "n_basis", "blend_rate")}
    print(f"\nchosen: {chosen}")
    if args.out:
        Path(args.out).write_text(table(rows) + f"\nchosen: {chosen}\n")
    if args.json:
        Path(args.json).write_text(json.dumps({"rows": rows, "chosen": chosen}, indent=1))
    return 0
