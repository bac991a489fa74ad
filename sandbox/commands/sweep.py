"""``python -m sandbox sweep``: leave-one-out of every configuration of a grid, ranked.

Prints the five best configurations; the exit status is 1 if a configuration
failed (its worker died twice), 2 for bad input. See :mod:`sandbox.eval.sweep`.
``--config FILE`` (written by ``tune --out``) sets the options the grid's
points start from; a point's own values replace them.
"""

from __future__ import annotations

from sandbox.commands import _executor, _observation, _settings, _types

NAME = "sweep"
HELP = ("leave-one-out of every configuration of a grid (YAML) on local processes or a Dask "
        "cluster; results ranked by the tuning objective")


def add_arguments(parser) -> None:
    """Add the ``sweep`` command's options to ``parser``."""
    parser.add_argument("--data", required=True,
                        help="a folder in the shared layout or synthetic:NAME")
    parser.add_argument("--grid", required=True, metavar="GRID.yaml",
                        help="options and their values: lists (Cartesian product) or "
                             "'points:' (see sandbox.eval.grid)")
    parser.add_argument("--out", required=True, metavar="DIR",
                        help="folder of the results (results/<key>.json, summary.md, "
                             "summary.json, summary.png); a re-run skips what is done")
    _executor.add_arguments(parser)
    parser.add_argument("--force", action="store_true",
                        help="write into an --out folder that holds another sweep")
    parser.add_argument("--tasks", default=None, help="comma-separated subset of tasks")
    parser.add_argument("--n-per-task", type=_types.PER_TASK, default=None,
                        help="trials per task (synthetic: generated; folder: first N)")
    parser.add_argument("--seed", type=_types.SEED, default=0, help="seed of synthetic data")
    _observation.add_arguments(parser)
    _settings.add_argument(parser)
    _observation.add_cache_argument(parser)


def run(args) -> int:
    """Run ``python -m sandbox sweep`` with the parsed ``args``; return the exit status."""
    from pathlib import Path

    from sandbox.eval.loocv import EvalConfig
    from sandbox.eval.sweep import sweep

    settings = _settings.load(args.config)
    args.observe = _settings.observe(args.observe, settings)
    spec = _observation.data_spec(args)
    summary = sweep(args.data, args.grid, args.out, force=args.force, seed=args.seed,
                    tasks=_observation.split(args.tasks), n_per_task=args.n_per_task,
                    spec=spec, observe=_observation.observe(args, spec),
                    base=EvalConfig(**_settings.eval_fields(settings)),
                    cache=_observation.cache(args),
                    **_executor.options(args))
    ranked, failed = summary["ranked"], summary["failed"]
    for entry in ranked[:5]:
        print(f"{entry['rank']:3d}. J = {entry['J']:.3f}  {entry['label']}")
    where = Path(args.out) / "summary.md"        # no "out//summary.md" for an --out ending in /
    print(f"{len(ranked)} configurations ranked, {len(failed)} failed -> {where}")
    return 1 if failed else 0
