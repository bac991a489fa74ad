"""``python -m sandbox compare``: every method on the same folds and stream, one table.

Runs the methods of :mod:`sandbox.methods` (``dynamic``, ``static``, ``bip``,
``ebip``, ``dtw``, ``nearest``) on identical leave-one-out folds (or, with
``--holdout N``, N held-out trials per task predicted with the true task given),
identical preprocessing and the same observation stream
(:mod:`sandbox.eval.compare`), and writes into ``--out DIR``:

* ``methods/<method>.json``: each method's per-trial results and row, written
  whole as the method finishes; a re-run skips a method whose options and data
  are unchanged (Ctrl-C keeps the methods done, and no partial file);
* ``compare.json`` and ``compare.md``: one row per method (e_p, e_q, e_phi,
  recognition at 30 %, 50 % and the end, late decay, median update time, each
  with a 95 % bootstrap interval);
* ``recognition.png``: recognition over the recording, one line per method.

``--observe`` and ``--data synthetic:NAME`` work as in ``evaluate``;
``--config FILE`` applies the settings ``tune --out`` wrote to every method.
"""

from __future__ import annotations

from sandbox.commands import _observation, _settings, _types

NAME = "compare"
HELP = ("dynamic and static IProMP beside BIP, eBIP, DTW and nearest-neighbour on the same "
        "folds and observation stream: one table")
DEFAULT_METHODS = "dynamic,static,bip,ebip,dtw,nearest"


def add_arguments(parser) -> None:
    """Add ``compare``'s options to its subparser."""
    parser.add_argument("--data", required=True,
                        help="a folder in the shared layout or synthetic:NAME "
                             "(diverging, objects, two_task)")
    parser.add_argument("--methods", default=DEFAULT_METHODS, metavar="NAMES",
                        help=f"comma-separated, among {DEFAULT_METHODS} (default: all)")
    parser.add_argument("--out", type=_types.output_folder, required=True, metavar="DIR",
                        help="folder of compare.json, compare.md, recognition.png and "
                             "methods/<method>.json; a re-run resumes per method")
    parser.add_argument("--force", action="store_true",
                        help="replace compare.json and compare.md of another comparison")
    parser.add_argument("--tasks", default=None, help="comma-separated subset of tasks")
    _observation.add_arguments(parser)
    _settings.add_argument(parser)
    parser.add_argument("--window", type=_types.SECONDS, default=0.2, metavar="S",
                        help="seconds between updates of every method but static "
                             "(default 0.2)")
    parser.add_argument("--ratio", type=_types.FRACTION, default=0.5, metavar="F",
                        help="observed fraction of the true duration before static's one "
                             "prediction (default 0.5)")
    parser.add_argument("--holdout", type=_types.integer(0, _types.MAX_PER_TASK), default=0,
                        metavar="N", help="hold out N trials per task (drawn with --seed), "
                        "each predicted by a model of its own task fitted on that task's "
                        "other trials: the true task is given (default 0: leave-one-out)")
    parser.add_argument("--workers", type=_types.WORKERS, default=2,
                        help=f"processes, 1 to {_types.MAX_WORKERS} (default 2)")
    parser.add_argument("--seed", type=_types.SEED, default=0,
                        help="seed of synthetic data, of the held-out draw and of eBIP")
    parser.add_argument("--n-per-task", type=_types.PER_TASK, default=None,
                        help="trials per task (synthetic: generated; folder: first N)")
    parser.add_argument("--no-progress", action="store_true",
                        help="no progress bars or status lines on stderr")
    _observation.add_cache_argument(parser)


def _config(args, observe):
    """The comparison's configuration, checked before any data is read."""
    from sandbox.eval.compare import CompareConfig
    from sandbox.eval.loocv import EvalConfig
    from sandbox.methods import check_methods

    methods = check_methods(args.methods, "--methods")
    settings = _settings.load(args.config)
    evaluation = EvalConfig(**{**_settings.eval_fields(settings), "windows": (args.window,),
                               "ratios": (args.ratio,)}, observe=observe)
    return CompareConfig(methods=methods, window=args.window, ratio=args.ratio,
                         holdout=args.holdout, seed=args.seed, evaluation=evaluation)


def check_tasks(tasks: list[str], holdout: int) -> None:
    """Recognition needs two tasks or more (unless the true task is given, ``--holdout``)."""
    if holdout == 0 and len(set(tasks)) < 2:
        raise ValueError(f"--data: expected at least two tasks for the recognition measures "
                         f"of a leave-one-out comparison, got one ({tasks[0]!r}); add tasks "
                         f"or give --holdout N (true task given, no recognition)")


def run(args) -> int:
    """Run ``python -m sandbox compare`` with the parsed ``args``; return the exit status."""
    from pathlib import Path

    from sandbox.eval.compare import run_compare, to_markdown, write_outputs
    from sandbox.eval.datasets import load_pair
    from sandbox.eval.progress import status
    from sandbox.methods import check_observable

    settings = _settings.load(args.config)
    args.observe = _settings.observe(args.observe, settings)
    spec = _observation.data_spec(args)
    observe = _observation.observe(args, spec)
    config = _config(args, observe)
    check_observable(config.methods, spec.observed(list(observe)), "--observe")
    out = Path(args.out)
    _check_out(out, args.force)
    train, test, skipped = load_pair(args.data, seed=args.seed,
                                     tasks=_observation.split(args.tasks),
                                     n_per_task=args.n_per_task, spec=spec, observe=observe,
                                     cache=_observation.cache(args),
                                     progress=not args.no_progress)
    if not train:
        from sandbox.data.skipped import no_usable

        raise no_usable(f"--data {args.data}", skipped)
    check_tasks([d.task for d in train], args.holdout)
    comparison = run_compare(train, test, config, out, workers=args.workers,
                             progress=not args.no_progress, dataset=str(args.data),
                             log=lambda text: status(text, not args.no_progress))
    for path in write_outputs(comparison, out):
        print(f"wrote {path}")
    print()
    print(to_markdown(comparison))
    return 0


def _check_out(out, force: bool) -> None:
    """``--out`` may hold an earlier comparison (resumed) but no other files, unless --force."""
    if force or not out.is_dir():
        return
    ours = {"compare.json", "compare.md", "recognition.png", "methods"}
    other = sorted(p.name for p in out.iterdir() if p.name not in ours
                   and not p.name.startswith("."))
    if other:
        raise ValueError(f"--out {str(out)!r}: expected an empty folder or one of an earlier "
                         f"comparison, got {', '.join(other[:3])}; pass --force to write there")
