"""``python -m sandbox fit --data DIR|synthetic:NAME --out model.npz``: fit and save task models.

Loads the demonstrations with :func:`sandbox.data.datasets.load_dataset`
(training demos are RTS-smoothed by default, ``--preprocess``), fits one
Interaction ProMP per task (:class:`sandbox.core.IProMP`) and saves it in the
core's format (``.npz`` + JSON metadata, no pickle). Prints what was fitted:
tasks, demos per task, nominal durations, the speed prior, the estimated human
observation noise.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

NAME = "fit"
HELP = "fit one Interaction ProMP per task on a dataset and save the model (.npz)."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--data", required=True, metavar="DIR|synthetic:NAME",
                        help="dataset folder <DIR>/<task>/<trial>.csv or synthetic:NAME")
    parser.add_argument("--out", required=True, metavar="PATH", help="model file to write (.npz)")
    parser.add_argument("--tasks", default=None, help="comma-separated subset of tasks")
    parser.add_argument("--n-basis", type=int, default=None,
                        help="basis functions per dim (default: IProMP's, 21)")
    parser.add_argument("--regularizer", type=float, default=None,
                        help="relative weight-covariance regulariser (core default)")
    parser.add_argument("--n-per-task", type=int, default=None,
                        help="demos per task (folder: the first N; synthetic: generated, 20)")
    parser.add_argument("--seed", type=int, default=0, help="seed of a synthetic set (0)")
    parser.add_argument("--preprocess", choices=("none", "causal", "smooth"), default="smooth",
                        help="human-track preprocessing of the demos (smooth)")
    parser.add_argument("--human-columns", default=None, metavar="A,B,C",
                        help="human columns of a folder (default human_left_hand_x,y,z)")
    parser.add_argument("--robot-columns", default=None, metavar="A,B,...",
                        help="robot columns of a folder (default left_s0 ... left_w2)")
    parser.add_argument("--force", action="store_true", help="overwrite an existing --out file")
    parser.add_argument("--json", action="store_true", help="print the fit summary as JSON")


def _split(text: str | None) -> list[str] | None:
    return None if text is None else [s.strip() for s in text.split(",") if s.strip()]


def run(args: argparse.Namespace) -> int:
    import warnings

    from sandbox.core import IProMP
    from sandbox.data.datasets import load_dataset
    from sandbox.data.recorded import Columns, SkippedTrialWarning

    out = Path(args.out)
    if out.exists() and not args.force:
        raise ValueError(f"--out: {out} exists; pass --force to overwrite it")
    if not out.parent.is_dir():
        raise ValueError(f"--out: expected a file in an existing folder, got {str(out)!r}")
    options = {}
    if args.human_columns or args.robot_columns:
        cols = {}
        if args.human_columns:
            cols["human"] = tuple(_split(args.human_columns))
        if args.robot_columns:
            cols["robot"] = tuple(_split(args.robot_columns))
        options["columns"] = Columns(**cols)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", SkippedTrialWarning)
        demos = load_dataset(args.data, seed=args.seed, tasks=_split(args.tasks),
                             n_per_task=args.n_per_task, preprocess=args.preprocess, **options)
    kwargs = {} if args.regularizer is None else {"regularizer": args.regularizer}
    if args.n_basis is not None:
        kwargs["n_basis"] = args.n_basis
    model = IProMP(**kwargs).fit(demos)
    model.save(out)
    summary = _summary(model, args, out, len(demos), [str(w.message) for w in caught])
    print(json.dumps(summary, indent=2) if args.json else _format(summary))
    return 0


def _summary(model, args: argparse.Namespace, out: Path, n_demos: int, skipped: list[str]):
    import numpy as np

    return {
        "data": str(args.data), "out": str(out), "preprocess": args.preprocess,
        "n_basis": model.basis.n_basis, "demos": n_demos, "skipped": skipped,
        "human_noise_std_m": [float(s) for s in np.sqrt(model.noise)],
        "tasks": {t.name: {"demos": t.n_demos, "nominal_duration_s": t.nominal_duration,
                           "alpha_std": t.alpha_std} for t in model.task_models},
    }


def _format(s: dict) -> str:
    lines = [f"Fitted {len(s['tasks'])} task models (N={s['n_basis']}) on {s['demos']} demos "
             f"from {s['data']} (preprocess={s['preprocess']})"]
    for name, t in s["tasks"].items():
        lines.append(f"  {name:<20}{t['demos']:>4} demos  T_nom {t['nominal_duration_s']:.2f} s"
                     f"  sigma_alpha {t['alpha_std']:.3f}")
    noise = ", ".join(f"{1e3 * v:.1f}" for v in s["human_noise_std_m"])
    lines.append(f"  human observation noise (mm): {noise}")
    lines += [f"  {w}" for w in s["skipped"]]
    lines.append(f"Saved {s['out']}")
    return "\n".join(lines)
