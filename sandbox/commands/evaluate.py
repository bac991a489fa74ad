"""``python -m sandbox evaluate``: the paper's experiments (leave-one-out) as ``report.json``."""

from __future__ import annotations

from sandbox.commands import _observation, _types

NAME = "evaluate"
HELP = "leave-one-out evaluation of the static and dynamic formulations (paper sec. 5)"


def add_arguments(parser) -> None:
    parser.add_argument("--data", required=True,
                        help="a folder in the shared layout or synthetic:NAME "
                             "(diverging, objects, two_task)")
    parser.add_argument("--tasks", default=None, help="comma-separated subset of tasks")
    _observation.add_arguments(parser)
    parser.add_argument("--windows", type=_types.WINDOWS, default="1,0.5,0.2,0.1",
                        help="dynamic windows dow_t (s), each in (0, 60]")
    parser.add_argument("--ratios", type=_types.RATIOS,
                        default="0.1,0.2,0.3,0.4,0.5,0.6,0.7,0.8,0.9",
                        help="observed ratios of the static formulation, each in (0, 1]")
    parser.add_argument("--workers", type=_types.WORKERS, default=2,
                        help=f"processes, 1 to {_types.MAX_WORKERS} (default 2)")
    parser.add_argument("--seed", type=_types.SEED, default=0, help="seed of synthetic data")
    parser.add_argument("--n-per-task", type=_types.PER_TASK, default=None,
                        help="trials per task (synthetic: generated; folder: first N)")
    parser.add_argument("--out", type=_types.output_file, required=True,
                        help="report.json to write")
    parser.add_argument("--plots", type=_types.output_folder, default=None,
                        help="folder for the PNG figures")
    parser.add_argument("--markdown", type=_types.output_file, default=None,
                        help="report.md to write")
    parser.add_argument("--no-progress", action="store_true",
                        help="no progress bars or status lines on stderr")
    parser.add_argument("--no-cache", action="store_true",
                        help="load and preprocess every trial file afresh, without the on-disk "
                             "cache of loaded trials (python -m sandbox data cache)")


def run(args) -> int:
    import json
    from pathlib import Path

    from sandbox.eval.datasets import load_pair
    from sandbox.eval.loocv import EvalConfig, run_loocv
    from sandbox.eval.progress import status
    from sandbox.eval.report import build_report, to_markdown

    spec = _observation.data_spec(args)
    observe = _observation.observe(args, spec)
    config = EvalConfig(ratios=args.ratios, windows=args.windows, observe=observe)
    train, test, skipped = load_pair(args.data, seed=args.seed,
                                     tasks=_observation.split(args.tasks),
                                     n_per_task=args.n_per_task, spec=spec, observe=observe,
                                     cache=not args.no_cache, progress=not args.no_progress)
    for reason in skipped:
        print(f"skipped: {reason}")
    if not train:
        raise ValueError(f"--data: no usable trial in {args.data} ({len(skipped)} skipped)")
    trials, runtime = run_loocv(train, test, config, workers=args.workers,
                                progress=not args.no_progress)
    status("report: metrics and bootstrap intervals", not args.no_progress)
    report = build_report(trials, config.to_dict(), str(args.data), runtime)
    Path(args.out).write_text(json.dumps(report, indent=1))
    print(f"{len(trials)} trials in {runtime:.1f} s -> {args.out}")
    if args.markdown:
        Path(args.markdown).write_text(to_markdown(report))
    if args.plots:
        from sandbox.eval.plots import plot_report

        for path in plot_report(report, args.plots):
            print(f"figure: {path}")
    _summary(report)
    return 0


def _summary(report: dict) -> None:
    print(f"\n{'':12s} {'e_p (m)':>9} {'e_q (rad)':>9} {'e_phi (s)':>9} {'recog':>6}")
    print(f"{'oracle':12s} {report['oracle']['mean']['e_p']:9.3f} "
          f"{report['oracle']['mean']['e_q']:9.3f} {0:9.3f}")
    for name, section in (("static", report["static"]), ("dynamic", report["dynamic"])):
        for key, entry in section.items():
            m = entry["mean"]
            label = f"{name} {key}" + ("" if name == "static" else " s")
            print(f"{label:12s} {m['e_p']:9.3f} {m['e_q']:9.3f} {m['e_phi']:9.3f} "
                  f"{m['recognition']:6.2f}")
