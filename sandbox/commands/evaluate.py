"""``python -m sandbox evaluate``: the paper's experiments (leave-one-out) as ``report.json``.

With ``--model FILE`` (a model saved by ``fit``) the evaluation is test-only:
every trial of ``--data`` is predicted by that model, nothing is refitted and
there is no leave-one-out (:mod:`sandbox.eval.heldout`); the report's
``config`` says ``mode: test-only`` and lists each trial's scores
(``per_trial``). ``--config FILE`` applies settings written by ``tune --out``.

Everything is checked before the work starts: the output paths (an existing
file needs ``--force``), the settings, the model against the modalities and
tasks asked for. A set with no usable trial is an error with one line that
counts the skipped trials by reason (``--verbose`` lists every file).
"""

from __future__ import annotations

from sandbox.commands import _model, _observation, _outputs, _settings, _skipped, _types

NAME = "evaluate"
HELP = "leave-one-out evaluation of the static and dynamic formulations (paper sec. 5)"
WINDOWS = "1,0.5,0.2,0.1"
RATIOS = "0.1,0.2,0.3,0.4,0.5,0.6,0.7,0.8,0.9"


def add_arguments(parser) -> None:
    parser.add_argument("--data", required=True,
                        help="a folder in the shared layout or synthetic:NAME "
                             "(diverging, objects, two_task)")
    parser.add_argument("--tasks", default=None, help="comma-separated subset of tasks")
    _observation.add_arguments(parser)
    _model.add_argument(parser, "predict every trial of --data with it (test-only: no refit, "
                                "no leave-one-out)")
    _settings.add_argument(parser)
    parser.add_argument("--windows", type=_types.WINDOWS, default=WINDOWS, metavar="S,S,...",
                        help="dynamic windows dow_t in seconds, comma-separated, each in "
                             f"(0, {_types.MAX_WINDOW_S:g}] (default {WINDOWS})")
    parser.add_argument("--ratios", type=_types.RATIOS, default=RATIOS, metavar="F,F,...",
                        help="observed fractions of the static formulation, comma-separated, "
                             f"each in (0, 1] (default {RATIOS})")
    parser.add_argument("--workers", type=_types.WORKERS, default=2,
                        help=f"processes, 1 to {_types.MAX_WORKERS} (default 2)")
    parser.add_argument("--seed", type=_types.SEED, default=0, help="seed of synthetic data")
    _observation.add_session_argument(parser)
    parser.add_argument("--n-per-task", type=_types.PER_TASK, default=None,
                        help="trials per task (synthetic: generated; folder: first N)")
    parser.add_argument("--out", type=_types.output_file, required=True,
                        help="report.json to write")
    parser.add_argument("--plots", type=_types.output_folder, default=None,
                        help="folder for the PNG figures")
    parser.add_argument("--markdown", type=_types.output_file, default=None,
                        help="report.md to write")
    _outputs.add_force(parser, "--out, --markdown and figure files")
    _skipped.add_argument(parser)
    parser.add_argument("--no-progress", action="store_true",
                        help="no progress bars or status lines on stderr")
    _observation.add_cache_argument(parser)


def _prepare(args):
    """Settings, model, modalities and config, all checked before any data is read."""
    from sandbox.eval.loocv import EvalConfig

    settings = _settings.load(args.config)
    model = _model.load(args.model) if args.model else None
    _outputs.check_new([("--out", args.out), ("--markdown", args.markdown),
                        *(("--plots", p) for p in _outputs.figures(args.plots))], args.force)
    spec = _observation.data_spec(args)
    asked = _settings.observe(args.observe, settings)
    if model is not None:
        option = "--observe" if args.observe is not None else "--config observe"
        observe = _model.observe(model, asked, option)
        spec.observed(list(observe))       # the spec can read them
        if args.tasks:
            _model.tasks(model, _observation.split(args.tasks), "--tasks")
        if not str(args.data).startswith("synthetic:"):     # a folder: its tasks are listed
            from sandbox.data.recorded import find_trials

            found = find_trials(args.data, _observation.split(args.tasks))
            _model.tasks(model, list(dict.fromkeys(t for t, _ in found)), args.data)
    else:
        args.observe = asked
        observe = _observation.observe(args, spec)
    config = EvalConfig(**_settings.eval_fields(settings), ratios=args.ratios,
                        windows=args.windows, observe=observe)
    return spec, observe, model, config


def run(args) -> int:
    import json

    from sandbox.eval.datasets import load_pair
    from sandbox.eval.progress import status
    from sandbox.eval.report import build_report, to_markdown

    spec, observe, model, config = _prepare(args)
    train, test, skipped = load_pair(args.data, seed=args.seed,
                                     tasks=_observation.split(args.tasks),
                                     n_per_task=args.n_per_task, spec=spec, observe=observe,
                                     cache=_observation.cache(args), progress=not args.no_progress,
                                     session=args.session)
    _skipped.report(skipped, args.verbose, len(train))
    if not train:
        raise _skipped.no_usable(args.data, skipped, verbose=args.verbose)
    progress = not args.no_progress
    if model is None:
        from sandbox.eval.loocv import run_loocv

        trials, runtime = run_loocv(train, test, config, workers=args.workers, progress=progress)
        described = config.to_dict()
    else:
        from sandbox.eval import heldout

        heldout.check_compatible(model, test)
        trials, runtime = heldout.run_heldout(model, train, test, config, workers=args.workers,
                                              progress=progress)
        described = heldout.describe(model, config, args.model)
    status("report: metrics and bootstrap intervals", progress)
    report = build_report(trials, described, str(args.data), runtime)
    if model is not None:
        report["per_trial"] = heldout.per_trial(trials)
    _write(args, report, json.dumps(report, indent=1), to_markdown(report))
    _summary(report)
    return 0


def _write(args, report: dict, text: str, markdown: str) -> None:
    """Figures first (the likeliest to fail), then the report and the Markdown, each whole."""
    if args.plots:
        from sandbox.eval.plots import plot_report

        for path in plot_report(report, args.plots):
            print(f"figure: {path}")
    _outputs.write_text(args.out, text)
    print(f"{sum(report['n_trials'].values())} trials in {report['runtime_s']:.1f} s "
          f"-> {args.out}")
    if args.markdown:
        _outputs.write_text(args.markdown, markdown)


def _summary(report: dict) -> None:
    config = report["config"]
    if config.get("mode") == "test-only":
        print(f"\ntest-only: every trial predicted by the model {config['model']} "
              "(no refit, no leave-one-out)")
    print(f"\n{'':12s} {'e_p (m)':>9} {'e_q (rad)':>9} {'e_phi (s)':>9} {'recog':>6}")
    print(f"{'oracle':12s} {report['oracle']['mean']['e_p']:9.3f} "
          f"{report['oracle']['mean']['e_q']:9.3f} {0:9.3f}")
    for name, section in (("static", report["static"]), ("dynamic", report["dynamic"])):
        for key, entry in section.items():
            m = entry["mean"]
            label = f"{name} {key}" + ("" if name == "static" else " s")
            print(f"{label:12s} {m['e_p']:9.3f} {m['e_q']:9.3f} {m['e_phi']:9.3f} "
                  f"{m['recognition']:6.2f}")
