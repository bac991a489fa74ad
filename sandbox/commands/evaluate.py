"""``python -m sandbox evaluate``: the paper's experiments (leave-one-out) as ``report.json``.

With ``--model FILE`` (a model saved by ``fit``) the evaluation is test-only:
every trial of ``--data`` is predicted by that model, nothing is refitted and
there is no leave-one-out (:mod:`sandbox.eval.heldout`); the report's
``config`` says ``mode: test-only`` and lists each trial's scores
(``per_trial``). ``--config FILE`` applies settings written by ``tune --out``.

With ``--test B`` the evaluation is cross-session
(:mod:`sandbox.eval.crosssession`): one model of every task is fitted on all
trials of ``--data`` (with the options the leave-one-out uses: ``--config``,
``--observe``), and every trial of B (a folder in the shared layout or
``synthetic:NAME``, as ``--data``) is predicted by it, as a test stream
(causal preprocessing). The report is the leave-one-out's, with ``config``
saying ``mode: cross-session``, ``train``, ``test``, ``n_train`` and ``n_test``,
and ``per_trial``. B's tasks must be among those of ``--data``; ``--tasks`` and
``--n-per-task`` apply to both; ``--test-seed`` is the seed of a synthetic B
(default ``--seed``: the same trials as a synthetic ``--data`` of that name);
``--session`` and ``--test-session`` are the recording sessions of a synthetic
``--data`` and ``--test`` (:mod:`sandbox.data.synthetic.session`; default none).

``--tail KIND`` writes an emulated motion tail (:mod:`sandbox.eval.tails`: the hand holding,
lingering, drifting back, stopping short, overshooting, a frozen tracker) onto every test
stream of the leave-one-out, after the trial's meeting; with ``--tail-in-training`` the
training demonstrations get it too (a session whose every trial has it). The report's
``config`` then says ``tail`` and ``tail_in_training``. Only for the leave-one-out of one set.

A ``--data`` folder of sessions, ``ROOT/<session>/<task>/<trial>.csv``, is
evaluated leave-one-session-out: each session predicted by a model fitted on
all the others. The report pools every trial, with ``config`` saying
``mode: leave-one-session-out`` and ``sessions``, ``per_trial`` naming each
trial's session, and ``per_session``: each session's e_p, e_q, e_phi,
recognition (and time-to-correct) at every ratio and window, equal to those of
``--data <the other sessions> --test <session>``. With ``--test``, a folder of
sessions given as ``--data`` is fitted on whole (all its sessions pooled).

Everything is checked before the work starts: the output paths (an existing
file needs ``--force``), the settings, the model against the modalities and
tasks asked for. A set with no usable trial is an error with one line that
counts the skipped trials by reason (``--verbose`` lists every file).
"""

from __future__ import annotations

from sandbox.commands import _model, _observation, _outputs, _settings, _skipped, _types

NAME = "evaluate"
HELP = ("leave-one-out (or cross-session) evaluation of the static and dynamic formulations "
        "(paper sec. 5)")
WINDOWS = "1,0.5,0.2,0.1"
RATIOS = "0.1,0.2,0.3,0.4,0.5,0.6,0.7,0.8,0.9"
#: ``--tail`` choices (:data:`sandbox.eval.tails.KINDS`, kept here so ``--help`` stays light).
TAILS = ("none", "hold", "linger", "drift_back", "stop_short", "overshoot", "freeze")


def add_arguments(parser) -> None:
    """Add the ``evaluate`` command's options to ``parser``."""
    parser.add_argument("--data", required=True,
                        help="a folder in the shared layout or synthetic:NAME "
                             "(diverging, objects, two_task); a folder of sessions "
                             "ROOT/<session>/<task>/<trial>.csv is evaluated "
                             "leave-one-session-out")
    parser.add_argument("--test", default=None, metavar="DIR|synthetic:NAME",
                        help="cross-session: fit on all of --data, predict every trial of "
                             "this set (its tasks among --data's; not with --model)")
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
    parser.add_argument("--test-seed", type=_types.SEED, default=None,
                        help="seed of a synthetic --test set (default: --seed)")
    _observation.add_session_argument(parser)
    parser.add_argument("--test-session", type=_types.SEED, default=None, metavar="S",
                        help="recording session of a synthetic --test set, an integer >= 0 "
                             "(default: none, today's data)")
    parser.add_argument("--tail", default=None, choices=TAILS,
                        help="write this emulated motion tail onto every test stream after "
                             "its meeting (leave-one-out only; default: none)")
    parser.add_argument("--tail-in-training", action="store_true",
                        help="with --tail: onto the training demonstrations too")
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
    """Settings, model, modalities, config and the sessions of a folder of sessions
    (``[]`` if none), all checked before any data is read."""
    from sandbox.eval.loocv import EvalConfig

    settings = _settings.load(args.config)
    sessions = _sessions(args)
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
    return spec, observe, model, config, sessions


def _sessions(args) -> list:
    """The session folders of a ``--data`` folder of sessions (``[]`` for one set), checked
    against ``--test``, ``--test-seed`` and ``--model``: one line for a combination that
    cannot run."""
    from pathlib import Path

    from sandbox.data.sessions import SET_LAYOUT, find_sessions

    _check_tail(args)
    if args.test is not None and args.model is not None:
        raise ValueError("--test: expected either --test (fit on --data, predict --test) or "
                         "--model (predict --data with a saved model), got both")
    if args.test_session is not None and args.test is None:
        raise ValueError(f"--test-session: expected with --test (the session of a synthetic "
                         f"--test set), got --test-session {args.test_session} without --test")
    if args.test_seed is not None and args.test is None:
        raise ValueError(f"--test-seed: expected with --test (the seed of a synthetic --test "
                         f"set), got --test-seed {args.test_seed} without --test")
    if args.test is not None and Path(args.test).is_dir() and find_sessions(args.test, "--test"):
        raise ValueError(f"--test: expected one set {SET_LAYOUT} or synthetic:NAME, got a "
                         f"folder of sessions {args.test!r}; give one session")
    if not Path(args.data).is_dir():
        return []
    sessions = find_sessions(args.data, "--data")
    if sessions and args.model is not None:
        raise ValueError(f"--model: expected --data to be one set {SET_LAYOUT}, got a folder "
                         f"of {len(sessions)} sessions {args.data!r}; give one session")
    if args.test is None and sessions:
        from sandbox.data.sessions import check_sessions

        check_sessions(args.data, "--data")
    return sessions


def _check_tail(args) -> None:
    """``--tail`` runs with the leave-one-out of one set only; ``--tail-in-training`` with it."""
    from pathlib import Path

    from sandbox.data.sessions import find_sessions

    tail = getattr(args, "tail", None)
    if getattr(args, "tail_in_training", False) and tail is None:
        raise ValueError("--tail-in-training: expected with --tail KIND, got it alone")
    if tail is None:
        return
    if args.test is not None or args.model is not None:
        raise ValueError(f"--tail: expected the leave-one-out of one set, got --tail {tail} "
                         f"with {'--test' if args.test is not None else '--model'}")
    if Path(args.data).is_dir() and find_sessions(args.data, "--data"):
        raise ValueError(f"--tail: expected the leave-one-out of one set, got a folder of "
                         f"sessions {args.data!r}")


def run(args) -> int:
    """Run ``python -m sandbox evaluate`` with the parsed ``args``; return the exit status."""
    import json

    from sandbox.eval.progress import status
    from sandbox.eval.report import build_report, to_markdown

    spec, observe, model, config, sessions = _prepare(args)
    load = dict(seed=args.seed, tasks=_observation.split(args.tasks),
                n_per_task=args.n_per_task, spec=spec, observe=observe,
                cache=_observation.cache(args), progress=not args.no_progress,
                session=args.session)
    if args.test is not None or sessions:
        trials, described, runtime = _cross(args, config, load)
    else:
        trials, described, runtime = _single(args, model, config, load)
    status("report: metrics and bootstrap intervals", not args.no_progress)
    dataset = str(args.data) if args.test is None else str(args.test)
    sessions_given = {k: v for k, v in (("session", args.session),
                                        ("test_session", args.test_session)) if v is not None}
    report = build_report(trials, {**described, **sessions_given}, dataset, runtime)
    if "mode" in described:
        from sandbox.eval import crosssession

        report["per_trial"] = crosssession.per_trial(trials)
        if described["mode"] == crosssession.LEAVE_ONE_SESSION_OUT:
            report["per_session"] = crosssession.per_session(trials)
    _write(args, report, json.dumps(report, indent=1), to_markdown(report))
    _summary(report)
    return 0


def _single(args, model, config, load: dict) -> tuple[list[dict], dict, float]:
    """Leave-one-out of ``--data``, or test-only with ``--model``: the per-trial results,
    the report's ``config`` and the wall time (s)."""
    from sandbox.eval.datasets import load_pair

    train, test, skipped = load_pair(args.data, **load, workers=args.workers)
    _skipped.report(skipped, args.verbose, len(train))
    if not train:
        raise _skipped.no_usable(args.data, skipped, verbose=args.verbose)
    if model is None:
        from sandbox.eval.loocv import run_loocv

        described = config.to_dict()
        if getattr(args, "tail", None) is not None:
            from sandbox.eval.tails import with_tail

            train, test = with_tail(train, test, args.tail, in_training=args.tail_in_training,
                                    settle_tol=config.settle_tol, arrive_tol=config.arrive_tol)
            described.update(tail=args.tail, tail_in_training=bool(args.tail_in_training))
        trials, runtime = run_loocv(train, test, config, workers=args.workers,
                                    progress=load["progress"])
        return trials, described, runtime
    from sandbox.eval import heldout

    heldout.check_compatible(model, test)
    trials, runtime = heldout.run_heldout(model, train, test, config, workers=args.workers,
                                          progress=load["progress"])
    return trials, heldout.describe(model, config, args.model), runtime


def _cross(args, config, load: dict) -> tuple[list[dict], dict, float]:
    """``--data A --test B`` (cross-session), or leave-one-session-out of a folder of
    sessions: the per-trial results, the report's ``config`` and the wall time (s)."""
    from sandbox.eval import crosssession as cs

    fit, skipped = cs.load_sets(args.data, **load)
    test, more = [], []
    if args.test is not None:
        seed = args.seed if args.test_seed is None else args.test_seed
        try:
            test, more = cs.load_sets(args.test, **{**load, "seed": seed,
                                                    "session": args.test_session})
        except ValueError as error:         # which set a bad --tasks or folder is
            raise ValueError(f"--test {args.test}: {error}") from None
    _skipped.report(skipped + more, args.verbose, sum(len(s.train) for s in fit + test))
    for where, sets, dropped in ((args.data, fit, skipped), (args.test, test, more)):
        for s in sets:
            if not s.train:
                raise _skipped.no_usable(where if len(sets) == 1 else f"{where}/{s.name}",
                                         dropped, verbose=args.verbose)
    if args.test is None:
        trials, runtime = cs.run_leave_one_session_out(fit, config, workers=args.workers,
                                                       progress=load["progress"])
        return trials, cs.describe_sessions(config, fit), runtime
    trials, runtime = cs.run_cross_session(fit, test[0], config, workers=args.workers,
                                           progress=load["progress"])
    return trials, cs.describe_cross(config, fit, test[0], str(args.data)), runtime


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
    elif config.get("mode") == "cross-session":
        print(f"\ncross-session: fitted on {config['train']} ({config['n_train']} trials), "
              f"predicted {config['test']} ({config['n_test']} trials)")
    elif config.get("mode") == "leave-one-session-out":
        print(f"\nleave-one-session-out over {len(config['sessions'])} sessions: "
              + ", ".join(f"{k} ({n})" for k, n in config["session_trials"].items()))
    rows = [(f"{name} {key}" + ("" if name == "static" else " s"), entry["mean"])
            for name, section in (("static", report["static"]), ("dynamic", report["dynamic"]))
            for key, entry in section.items()]
    width = max([len("oracle")] + [len(label) for label, _ in rows])   # the labels line up
    from sandbox.eval.report import fmt  # e_q: "n/a" for a task-space robot part
    print(f"\n{'':{width}s} {'e_p (m)':>9} {'e_q (rad)':>9} {'e_phi (s)':>9} {'recog':>6} "
          f"{'share':>6}   (recognition: task-averaged, and the share of trials)")
    print(f"{'oracle':{width}s} {report['oracle']['mean']['e_p']:9.3f} "
          f"{fmt(report['oracle']['mean']['e_q']):>9} {0:9.3f}")
    for label, m in rows:
        print(f"{label:{width}s} {m['e_p']:9.3f} {fmt(m['e_q']):>9} {m['e_phi']:9.3f} "
              f"{m['recognition']:6.2f} {m.get('recognition_share', float('nan')):6.2f}")
    _sessions_summary(report)


def _sessions_summary(report: dict) -> None:
    """Each session's figures at the report's best window (gamma equal) and middle ratio."""
    if "per_session" not in report:
        return
    window = report["best_window"][next(iter(report["best_window"]))]
    ratios = list(report["static"])
    ratio = ratios[len(ratios) // 2]
    print(f"\nby session (dynamic {window} s | static {ratio}): e_p (m), recognition")
    for name, entry in report["per_session"].items():
        dyn, sta = entry["dynamic"][window], entry["static"][ratio]
        print(f"  {name:20s} {sum(entry['n_trials'].values()):4d} trials  "
              f"{dyn['e_p']:6.3f} {dyn['recognition']:5.2f} | {sta['e_p']:6.3f} "
              f"{sta['recognition']:5.2f}")
