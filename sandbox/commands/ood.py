"""``python -m sandbox ood``: does the familiarity warning fire on motions unlike the training ones?

Three modes, one report (:mod:`sandbox.eval.oodreport`):

* ``--data NORMAL --ood-data OOD [--ood-data OOD2 ...]``: a model is fitted on
  NORMAL; every NORMAL trial is scored by a model fitted without it and ranked
  against the calibration of the other trials (leave-one-out, so the false
  alarms are those of unseen normal motions); every OOD trial by the model of
  all NORMAL trials (:mod:`sandbox.eval.oodsets`). OOD is a folder, a
  ``minari:ID`` or a synthetic OOD family ``synthetic-ood:FAMILY[@BASE]``
  (:mod:`sandbox.data.synthetic.ood`: pause, speed, endpoint, other, still).
* ``--model M --data NORMAL --ood-data OOD``: M (saved by ``fit --calibrate``)
  streams both; NORMAL must be motions M was not fitted on (another seed or
  session, held-out recordings).
* ``--data DIR`` alone: leave-task-out (:mod:`sandbox.eval.ood`): each task in
  turn is the OOD set of a model fitted on the others.

The report gives, per OOD set (or left-out task) and pooled, the detection
before the handover at false-alarm rates of 1, 2, 5 and 10 % on the held-out
normal motions, the AUC, the median delay of a detection relative to the
handover moment (negative: before it) and what the calibration's own
threshold (``--alpha``) does. ``--out`` writes it as JSON (with every motion's
familiarity; ``--records`` re-reports such a file without rescoring),
``--markdown`` as tables (also printed), ``--plot`` the ROC curves (PNG).

Cost: one causal stream per trial, about 0.5-2 s each on one core (more with
more modalities): 20 synthetic trials per task of 5 tasks and 5 OOD sets is
560 streams, ~7 minutes on one busy core; the leave-task-out of the shared
recorded set streams its 174 trials 4 times (~4 minutes with 2 workers, hand only;
20 minutes to an hour with hand,arm,emg, depending on the machine's load).
"""

from __future__ import annotations

import argparse

from sandbox.commands import _model, _observation, _outputs, _skipped, _types

NAME = "ood"
HELP = ("out-of-distribution test of the familiarity warning: detection before the handover "
        "at 1-10 percent false alarms, AUC, delays, ROC (minutes to an hour; see --help)")
MODES = ("leave-task-out", "ood-sets", "model")
DESCRIPTION = """\
Does the familiarity warning fire on motions unlike the training ones, before the handover?

  --data NORMAL --ood-data OOD [--ood-data OOD2 ...]
      fit on NORMAL; each NORMAL trial is scored by a model fitted without it and
      ranked against the calibration of the other trials (leave-one-out: false
      alarms of unseen normal motions); each OOD trial by the model of all NORMAL
      trials. OOD: a folder, minari:ID or synthetic-ood:FAMILY[@BASE] with FAMILY
      one of pause, speed, endpoint, other, still (BASE diverging or objects).
  --model M --data NORMAL --ood-data OOD
      M (saved by fit --calibrate) streams both; NORMAL must be held out of M.
  --data DIR
      leave-task-out: each task in turn is the OOD set of a model of the others.

Reports, per OOD set (or left-out task) and pooled: detection before the
handover at 1, 2, 5 and 10 percent false alarms on the held-out normal motions,
AUC, the median delay of a detection relative to the handover (negative:
before it), and what the calibration's own threshold (--alpha) does.

How long: one causal stream per trial, 0.5-2 s each on one core. 20 synthetic
trials per task of 5 tasks against 5 OOD sets is 560 streams, about 7 minutes
on one busy core; the leave-task-out of the 174 recorded trials streams each 4
times: about 4 minutes (hand, 2 workers), 20 minutes to an hour (hand,arm,emg)
on 2 cores, depending on their load.
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the ``ood`` command's options to ``parser``."""
    parser.description = DESCRIPTION
    parser.formatter_class = argparse.RawDescriptionHelpFormatter
    parser.add_argument("--data", default=None, metavar="DIR|synthetic:NAME",
                        help="the normal motions: a folder in the shared layout or "
                             "synthetic:NAME (fitted on, unless --model)")
    parser.add_argument("--ood-data", action="append", default=None, metavar="SET",
                        help="an out-of-distribution set: a folder, minari:ID or "
                             "synthetic-ood:FAMILY[@BASE] (pause, speed, endpoint, other, "
                             "still); repeat for several; none: leave-task-out")
    _model.add_argument(parser, "stream --data and --ood-data with it, ranked by its own "
                                "calibration (fit --calibrate); --data must be held out of it")
    _observation.add_arguments(parser)
    parser.add_argument("--n-per-task", type=_types.PER_TASK, default=None,
                        help="trials per task (synthetic: generated, 20; folder: first N)")
    parser.add_argument("--seed", type=_types.SEED, default=0,
                        help="seed of synthetic sets (OOD families draw from their own "
                             "child stream of it)")
    parser.add_argument("--dow-t", type=_types.SECONDS, default=0.2, metavar="S",
                        help="update window in seconds (0.2; with --model: its calibration's)")
    parser.add_argument("--alpha", type=_types.FRACTION, default=0.05,
                        help="calibration level of the 'calibrated' columns (0.05; with "
                             "--model: its calibration's threshold)")
    parser.add_argument("--score", choices=("timing", "goal", "position", "all"),
                        default="timing",
                        help="what the familiarity ranks: the Mahalanobis term and the four "
                             "timing statistics (default), those and the goal (where the hand "
                             "is heading), the position (where it is against the task at its "
                             "phase) or both (calibrate(score=...)); with --model: its "
                             "calibration's")
    parser.add_argument("--end-prob", type=_types.bounded("end_prob"), default=None, metavar="P",
                        help="calibrate and rank only the updates before each motion's "
                             "estimated end (once the probability that it ended reached P, "
                             "e.g. 0.5; calibrate(end_prob=P)); default every update; with "
                             "--model: its calibration's")
    parser.add_argument("--cells", choices=("own", "chosen"), default="own",
                        help="file each calibration motion's updates under its own task "
                             "(default: the labels are used in calibration only) or under the "
                             "task chosen at each update (before; calibrate(cells=...)); with "
                             "--model: its calibration's")
    parser.add_argument("--workers", type=_types.WORKERS, default=1,
                        help=f"processes, 1 to {_types.MAX_WORKERS} (default 1)")
    parser.add_argument("--out", type=_types.output_file, default=None,
                        help="JSON report to write (with every motion's familiarity)")
    parser.add_argument("--markdown", type=_types.output_file, default=None,
                        help="Markdown tables to write (they are printed anyway)")
    parser.add_argument("--plot", type=_types.output_file, default=None,
                        help="ROC curves to write (PNG)")
    parser.add_argument("--records", default=None, metavar="FILE",
                        help="re-report the motions of a previous --out file (no scoring)")
    _outputs.add_force(parser, "--out, --markdown and --plot")
    _skipped.add_argument(parser)
    parser.add_argument("--no-progress", action="store_true",
                        help="no progress bars or status lines on stderr")
    _observation.add_cache_argument(parser)


def _check(args) -> None:
    """One ``ValueError`` line for a combination that cannot run, before any work."""
    if (args.data is None) == (args.records is None):
        raise ValueError("--data: expected the normal motions (--data) or a previous report "
                         "(--records), got " + ("both" if args.data else "neither"))
    if args.records and (args.ood_data or args.model):
        raise ValueError("--records: re-reports a saved file; expected no --ood-data or --model")
    if args.model and not args.ood_data:
        raise ValueError("--model: expected --ood-data too (leave-task-out refits the model, "
                         "a saved model cannot leave a task out)")
    _outputs.check_new([("--out", args.out), ("--markdown", args.markdown),
                        ("--plot", args.plot)], args.force)


def run(args: argparse.Namespace) -> int:
    """Run ``python -m sandbox ood`` with the parsed ``args``; return the exit status."""
    import json
    import time

    from sandbox.eval import oodreport

    _check(args)
    start = time.perf_counter()
    if args.records:
        saved = _read_records(args.records)
        about = {k: saved.get(k) for k in ("mode", "data", "ood_data", "observe", "dow_t",
                                            "score", "end_prob", "cells")}
        about["mode"] = about["mode"] or MODES[0]
        records, seconds = saved["records"], float(saved.get("seconds", 0.0))
    else:
        about, records = _score(args)
        seconds = time.perf_counter() - start
    result = {**about, "alpha": args.alpha, "seconds": seconds, "n_streams": len(records),
              "groups": oodreport.summarize(records, alpha=args.alpha), "records": records}
    text = oodreport.markdown(result)
    if args.plot:
        from sandbox.eval.plots import plot_roc

        print(f"figure: {plot_roc(result, args.plot)}")
    if args.out:
        _outputs.write_text(args.out, json.dumps(result))
    if args.markdown:
        _outputs.write_text(args.markdown, text)
    print(text, end="")
    return 0


def _read_records(path: str) -> dict:
    import json

    try:
        with open(path, encoding="utf-8") as file:
            saved = json.load(file)
    except json.JSONDecodeError as error:
        raise ValueError(f"--records: {path} is not JSON ({error.msg})") from None
    if not isinstance(saved, dict) or not isinstance(saved.get("records"), list):
        raise ValueError(f"--records: expected a report written by 'ood --out', got {path}")
    return saved


def _score(args) -> tuple[dict, list[dict]]:
    """Load the sets, score every motion, rank them: the report's header and the records."""
    from sandbox.eval import ood, oodsets
    from sandbox.eval.loocv import EvalConfig

    spec = _observation.data_spec(args)
    model = _model.load(args.model) if args.model else None
    observe = (_model.observe(model, args.observe) if model is not None
               else _observation.observe(args, spec))
    progress = not args.no_progress
    normal = _load(args, args.data, spec, observe, progress)
    sets = {s: _load(args, s, spec, observe, progress) for s in args.ood_data or []}
    config = EvalConfig(observe=observe)
    about = {"data": str(args.data), "ood_data": list(sets), "observe": ",".join(observe),
             "dow_t": args.dow_t}
    if model is not None:
        cal = model.calibration
        records = oodsets.score_with_model(model, normal, sets, config, progress=progress)
        return {**about, "mode": MODES[2], "dow_t": cal.dow_t if cal else args.dow_t}, records
    if sets:
        records = oodsets.score_sets(*normal, sets, config, dow_t=args.dow_t,
                                     workers=args.workers, progress=progress)
        return ({**about, "mode": MODES[1], "score": args.score, "end_prob": args.end_prob,
                 "cells": args.cells},
                ood.rank(records, score=args.score, gate=args.end_prob, cells=args.cells))
    train, test = normal
    if len({d.task for d in train}) < 3:
        raise ValueError(f"--data: leave-task-out needs at least three tasks (two stay "
                         f"trained), got {sorted({d.task for d in train})}; give --ood-data")
    records = ood.score_all(train, test, config, dow_t=args.dow_t, workers=args.workers,
                            progress=progress)
    return ({**about, "mode": MODES[0], "score": args.score, "end_prob": args.end_prob,
             "cells": args.cells},
            ood.rank(records, score=args.score, gate=args.end_prob, cells=args.cells))


def _load(args, data: str, spec, observe, progress: bool) -> tuple[list, list]:
    """``(train, test)`` of one set (smoothed and causal), skipped trials reported."""
    from sandbox.eval.datasets import load_pair

    train, test, skipped = load_pair(data, seed=args.seed, n_per_task=args.n_per_task,
                                     spec=spec, observe=list(observe),
                                     cache=_observation.cache(args), progress=progress)
    _skipped.report(skipped, args.verbose, len(train))
    if not train:
        raise _skipped.no_usable(data, skipped, verbose=args.verbose)
    return train, test
