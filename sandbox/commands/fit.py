"""``python -m sandbox fit --data DIR|synthetic:NAME --out model.npz``: fit and save task models.

Loads the demonstrations with :func:`sandbox.data.datasets.load_dataset`
(training demos are RTS-smoothed by default, ``--preprocess``; ``--observe``
and ``--spec`` choose the modalities; ``--session S`` a synthetic set's
recording session), fits one Interaction ProMP per task
(:class:`sandbox.core.IProMP`) and saves it in the core's format (``.npz`` +
JSON metadata, no pickle). Prints what was fitted: tasks, demos per task,
nominal durations, the speed prior, the estimated observation noise of every
modality and the scale of signal modalities. ``--config FILE`` applies the
model options and ``observe`` of a settings file written by ``tune --out``
(``--n-basis``, ``--regularizer`` and ``--observe`` override it). A set with no
usable trial is one error line counting the skipped trials by reason
(``--verbose`` lists every file).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from sandbox.commands import _observation, _settings, _skipped, _types

NAME = "fit"
HELP = "fit one Interaction ProMP per task on a dataset and save the model (.npz)."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the ``fit`` command's options to ``parser``."""
    parser.add_argument("--data", required=True, metavar="DIR|synthetic:NAME",
                        help="dataset folder <DIR>/<task>/<trial>.csv or synthetic:NAME")
    parser.add_argument("--out", type=_types.output_file, required=True, metavar="PATH",
                        help="model file to write (.npz)")
    parser.add_argument("--tasks", default=None, help="comma-separated subset of tasks")
    parser.add_argument("--n-basis", type=_types.N_BASIS, default=None,
                        help=f"basis functions per dim, 2 to {_types.MAX_N_BASIS} "
                             "(default: IProMP's, 21)")
    parser.add_argument("--regularizer", type=_types.REGULARIZER, default=None,
                        help="relative weight-covariance regulariser, > 0 (core default)")
    parser.add_argument("--n-per-task", type=_types.PER_TASK, default=None,
                        help="demos per task (folder: the first N; synthetic: generated, 20)")
    parser.add_argument("--seed", type=_types.SEED, default=0, help="seed of a synthetic set (0)")
    _observation.add_session_argument(parser)
    parser.add_argument("--preprocess", choices=("none", "causal", "smooth"), default="smooth",
                        help="human-track preprocessing of the demos (smooth)")
    _observation.add_arguments(parser)
    _observation.add_cache_argument(parser)
    _settings.add_argument(parser)
    parser.add_argument("--force", action="store_true", help="overwrite an existing --out file")
    parser.add_argument("--json", action="store_true", help="print the fit summary as JSON")
    parser.add_argument("--calibrate", action="store_true",
                        help="also calibrate the predictors' familiarity (an 'unsure / unknown "
                             "motion' warning in the viewer and teleop): every demo streamed "
                             "causally and scored by a model fitted without it (a leave-one-out; "
                             "needs 3+ demos per task)")
    parser.add_argument("--score", choices=("timing", "goal", "position", "all"), default=None,
                        help="with --calibrate: what the familiarity ranks, as ood --score "
                             "(default timing)")
    parser.add_argument("--end-prob", type=_types.bounded("end_prob"), default=None,
                        metavar="P", help="with --calibrate: calibrate only the updates before "
                                          "each motion's estimated end, as ood --end-prob")
    _skipped.add_argument(parser)


def run(args: argparse.Namespace) -> int:
    """Run ``python -m sandbox fit`` with the parsed ``args``; return the exit status."""
    import warnings

    from sandbox.core import IProMP
    from sandbox.data.datasets import load_dataset
    from sandbox.data.geometry import attach_geometry
    from sandbox.data.recorded import SkippedTrialWarning

    out = Path(args.out)
    if out.exists() and not args.force:
        raise ValueError(f"--out: {out} exists; pass --force to overwrite it")
    if not args.calibrate and (args.score is not None or args.end_prob is not None):
        raise ValueError("--score/--end-prob: expected --calibrate with them (they choose how "
                         "the familiarity is calibrated), got them without it")
    if args.calibrate and args.preprocess != "smooth":
        raise ValueError("--calibrate: expected --preprocess smooth (the demos the streams are "
                         f"paired with), got {args.preprocess!r}")
    settings = _settings.load(args.config)
    kwargs = _settings.model_options(settings, n_basis=args.n_basis,
                                     regularizer=args.regularizer)
    model = IProMP(**kwargs)                   # options checked before the data is read
    args.observe = _settings.observe(args.observe, settings)
    spec = _observation.data_spec(args)
    observe = _observation.observe(args, spec)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", SkippedTrialWarning)
        demos = load_dataset(args.data, spec=spec, observe=observe, seed=args.seed,
                             tasks=_observation.split(args.tasks), n_per_task=args.n_per_task,
                             preprocess=args.preprocess, cache=_observation.cache(args),
                             session=args.session)
    skipped = [str(w.message) for w in caught if issubclass(w.category, SkippedTrialWarning)]
    _skipped.report(skipped, args.verbose, len(demos))
    if not demos:
        raise _skipped.no_usable(args.data, skipped, "demonstration", args.verbose)
    model.fit(demos)
    if args.calibrate:
        _calibrate(model, demos, args, spec, observe)
    attach_geometry(model, demos)
    out.parent.mkdir(parents=True, exist_ok=True)       # missing folders are made, as by play
    model.save(out)
    summary = _summary(model, args, out, len(demos), skipped)
    summary["noise_floor"] = _floors(model, demos)
    print(json.dumps(summary, indent=2) if args.json else _format(summary))
    return 0


def _calibrate(model, demos, args, spec, observe) -> None:
    """Familiarity calibration on the demos' causal streams (as the predictors receive them)."""
    from sandbox.data.datasets import load_dataset

    streams = load_dataset(args.data, spec=spec, observe=observe, seed=args.seed,
                           tasks=_observation.split(args.tasks), n_per_task=args.n_per_task,
                           preprocess="causal", cache=_observation.cache(args),
                           session=args.session)
    by_source = {s.source: s for s in streams}
    kept = [d for d in demos if d.source in by_source]
    if len(kept) != len(demos):
        raise ValueError(f"--calibrate: {len(demos) - len(kept)} demos have no causal stream")
    cal = model.calibrate(demos, [by_source[d.source] for d in demos],
                          score=args.score or "timing", end_prob=args.end_prob)
    print(f"familiarity calibrated on {len(demos)} held-out streams "
          f"(threshold {cal.threshold:.3g}, alpha {cal.alpha:g})")


def _summary(model, args: argparse.Namespace, out: Path, n_demos: int, skipped: list[str]):
    import numpy as np

    return {
        "data": str(args.data), "session": args.session, "out": str(out),
        "preprocess": args.preprocess,
        "n_basis": model.basis.n_basis, "demos": n_demos, "skipped": skipped,
        "observe": [m.name for m in model.modalities], "robot_space": model.robot_space,
        "noise_std": {m.name: [float(s) for s in np.sqrt(model.noise[sl]) * model.scale[sl]]
                      for m, sl in zip(model.modalities, _slices(model))},
        "condition_noise_std": (None if model.condition_noise is None else {
            m.name: [float(s) for s in np.sqrt(model.condition_noise[sl]) * model.scale[sl]]
            for m, sl in zip(model.modalities, _slices(model))}),
        "units": {m.name: m.units for m in model.modalities},
        "signal_scale": {m.name: [float(v) for v in model.scale[sl]]
                         for m, sl in zip(model.modalities, _slices(model))
                         if m.kind == "signal"},
        "tasks": {t.name: {"demos": t.n_demos, "nominal_duration_s": t.nominal_duration,
                           "alpha_std": t.alpha_std} for t in model.task_models},
        "meeting_geometry": _geometry(model),
        "span_reg": {"choice": model.span_reg, "modalities": {
            k: {"variance": v["variance"], "factor": v["factor"]}
            for k, v in model.span_report.items()}},
    }


def _floors(model, demos) -> dict:
    """Each position modality's raw jitter and the floor the fit used
    (:mod:`sandbox.data.noisefloor`)."""
    from sandbox.core.modality import slices
    from sandbox.data.noisefloor import floor_summary

    out = floor_summary(demos, noise_floor=model.noise_floor, jitter_floor=model.jitter_floor,
                        noise_floors=model.noise_floors)
    where = slices(model.modalities)
    for name, entry in out.items():
        entry["floor_m"] = float(model.floors_used[where[name]][0])
    return out


def _geometry(model) -> dict:
    """Per task the learned hand-to-fingertip offset (m) and its spread, or the note."""
    import numpy as np

    from sandbox.data.geometry import geometry_of

    geometry, note = geometry_of(model)
    if note is not None:
        return {"note": note}
    return {t: {"offset_m": np.round(g.mean, 4).tolist(),
                "spread_m": round(float(np.sqrt(np.trace(g.cov))), 4), "demos": g.count}
            for t, g in geometry.tasks.items()}


def _slices(model) -> list[slice]:
    from sandbox.core.modality import slices

    return list(slices(model.modalities).values())


def _format(s: dict) -> str:
    n = len(s['tasks'])
    lines = [f"Fitted {n} task model{'s' if n != 1 else ''} (N={s['n_basis']}) on "
             f"{s['demos']} demos from {s['data']}"
             f"{'' if s['session'] is None else ' session ' + str(s['session'])} "
             f"(observe={','.join(s['observe'])}, "
             f"preprocess={s['preprocess']})"]
    for name, t in s["tasks"].items():
        lines.append(f"  {name:<20}{t['demos']:>4} demos  T_nom {t['nominal_duration_s']:.2f} s"
                     f"  sigma_alpha {t['alpha_std']:.3f}")
    for name, noise in s["noise_std"].items():
        if s["units"][name] == "m":
            values, unit = ", ".join(f"{1e3 * v:.1f}" for v in noise), "mm"
        else:
            values, unit = ", ".join(f"{v:.3g}" for v in noise), s["units"][name]
        lines.append(f"  {name} observation noise ({unit}): {values}")
    for name, noise in (s["condition_noise_std"] or {}).items():
        values = ", ".join(f"{1e3 * v:.1f}" if s["units"][name] == "m" else f"{v:.3g}"
                           for v in noise)
        unit = "mm" if s["units"][name] == "m" else s["units"][name]
        lines.append(f"  {name} conditioning noise ({unit}, the robot's, eq. 7-9): {values}")
    if "noise_floor" in s:
        from sandbox.data.noisefloor import format_floors

        lines += format_floors(s["noise_floor"])
    for name, e in s["span_reg"]["modalities"].items():
        lines.append(f"  {name} weight regulariser at least {e['factor']:g} x its out-of-span "
                     f"variance {e['variance'] or 0:.3g} (span_reg={s['span_reg']['choice']})")
    if s["robot_space"] == "task":
        lines.append("  robot part in task space (m): e_p is measured on it directly, e_q "
                     "does not apply; episodes and play follow it through the arm's inverse "
                     "kinematics")
    geometry = s["meeting_geometry"]
    if "note" in geometry:
        lines.append(f"  meeting geometry: {geometry['note']}")
    for name, g in ({} if "note" in geometry else geometry).items():
        offset = ", ".join(f"{1e3 * v:+.0f}" for v in g["offset_m"])
        lines.append(f"  {name:<20}hand-to-fingertip at the meeting ({offset}) mm, spread "
                     f"{1e3 * g['spread_m']:.0f} mm")
    if s["skipped"]:
        lines.append(f"  {_skipped.summary(s['skipped'])}")
    lines.append(f"Saved {s['out']}")
    return "\n".join(lines)
