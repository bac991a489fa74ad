"""``python -m sandbox data summary|check-filter|export --data DIR``: what a recorded set contains.

``summary`` prints the tasks, trial counts, durations, sample rates (rows/s
and distinct tracker frames/s of the first observed position modality, the
hand by default), the new samples per second of every observed modality
(``--observe``), the tracker glitches found (repeated time stamps, re-sent frames, jumps, zero
rows, missing values, frozen skeletons, gate rejections of the causal
filter), the rows dropped and the trials skipped with their reasons, and,
when the synthetic generator is available, how a synthetic set compares with
the recordings. ``--json`` prints the same as JSON.

``check-filter`` measures the hand filter's settings on the set: every third
tracker frame of the first 60 % of each trial is hidden and predicted by the
RTS smoother and by the causal filter from the others (every 3-D point of the
observed position modalities).

``cache`` shows where the on-disk cache of loaded trials is and how big it
is (:mod:`sandbox.data.cache`); ``--clear`` empties it.

``export`` writes a folder's or a synthetic set's demonstrations as a Minari
dataset (``--minari-id sandbox/NAME-v0``; layout in :mod:`sandbox.data.minari_io`,
written by :mod:`sandbox.episodes.minari_export`), which ``fit --data minari:ID`` fits from.
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from sandbox.commands import _observation, _skipped, _types

NAME = "data"
HELP = ("inspect a recorded dataset: summary of trials and tracker glitches, filter check; "
        "export demonstrations as a Minari dataset.")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the ``data`` command's options to ``parser``."""
    sub = parser.add_subparsers(dest="data_command", metavar="ACTION", required=True)
    summary = sub.add_parser(
        "summary", help="tasks, durations, rates, glitches, skipped trials",
        description="Summarise a recorded set beside a synthetic one: per task the trials, "
                    "durations and sample rates, the tracker glitches found, every trial "
                    "skipped with its reason (one line each), and a frame: block placing the "
                    "demos' meeting region in Baxter's reach. With no usable trial, one line "
                    "per reason (--verbose: per file).")
    _common(summary)
    summary.add_argument("--json", action="store_true", help="print JSON instead of text")
    summary.add_argument("--no-progress", action="store_true",
                         help="no progress bar on stderr")
    _skipped.add_argument(summary)
    summary.add_argument(
        "--synthetic", default="objects", metavar="NAME",
        help="synthetic set to compare with the recordings (default objects; 'none' to skip)",
    )
    check = sub.add_parser(
        "check-filter", help="held-out error of the hand filter settings",
        description="Score the hand tracker filter's settings on a recorded set: every third "
                    "tracker frame of the first 60 % of each trial is hidden, the filter runs on "
                    "the rest, and the smoothed and causal estimates' errors at the hidden "
                    "frames are printed for the given (or default) settings.")
    _common(check)
    check.add_argument("--accel-std", type=_filter("accel_std"), default=None,
                       help="m s^-1.5, > 0 (default 6)")
    check.add_argument("--noise-std", type=_filter("noise_std"), default=None,
                       help="m, > 0 (default 0.003)")
    check.add_argument("--jitter-std", type=_filter("time_jitter_std", 1.0, open_low=False),
                       default=None, help="s, in [0, 1] (default 0.01)")
    check.add_argument("--gate-prob", type=_filter("gate_prob", 1.0), default=None,
                       help="in (0, 1] (default 0.999)")
    check.add_argument("--json", action="store_true", help="print JSON instead of text")
    cache = sub.add_parser(
        "cache", help="where the cache of loaded trials is, its size; --clear",
        description="Show where the cache of loaded trials lives (fit, evaluate, tune and sweep "
                    "reuse preprocessed trials from it) and how big it is; --clear empties it.")
    cache.add_argument("--clear", action="store_true", help="delete every cached trial")
    _add_export(sub)


def _add_export(sub) -> None:
    """``data export``: demonstrations as a Minari dataset (optional extra)."""
    export = sub.add_parser("export", help="write demonstrations as a Minari dataset "
                                           '(pip install -e ".[minari]")',
                            description="Write demonstrations (a recorded folder or a synthetic "
                                        "set) as a Minari dataset of the handover environment's "
                                        "observations and joint-target actions; fit --data "
                                        "minari:ID reads it back. Needs "
                                        'pip install -e ".[minari]".')
    export.add_argument("--data", required=True, metavar="DIR|synthetic:NAME",
                        help="dataset folder <DIR>/<task>/<trial>.csv or synthetic:NAME")
    export.add_argument("--minari-id", required=True, metavar="ID",
                        help="Minari dataset id, e.g. sandbox/objects-v0 (written under "
                             "MINARI_DATASETS_PATH, default ~/.minari/datasets)")
    export.add_argument("--tasks", default=None, help="comma-separated subset of tasks")
    export.add_argument("--n-per-task", type=_types.PER_TASK, default=None,
                        help="demos per task (folder: the first N; synthetic: generated, 20)")
    export.add_argument("--seed", type=_types.SEED, default=0, help="seed of a synthetic set")
    export.add_argument("--preprocess", choices=("none", "causal", "smooth"), default="smooth",
                        help="human-track preprocessing stored in the dataset (smooth, as fit)")
    export.add_argument("--env-id", default=None, metavar="ID",
                        help="environment the dataset points at (default: the diverging one "
                             "for synthetic:diverging, sandbox/BaxterHandover-v1 otherwise)")
    export.add_argument("--force", action="store_true", help="replace an existing dataset")
    _observation.add_arguments(export)


def _filter(field: str, high: float = float("inf"), *, open_low: bool = True):
    """The type of an option setting ``FilterConfig.<field>``."""
    return _types.number(0.0, high, open_low=open_low, meaning=f"FilterConfig {field}")


def _common(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--data", required=True, metavar="DIR",
                        help="dataset folder <DIR>/<task>/<trial>.csv, or laid out as --spec "
                             "says (files, labels)")
    parser.add_argument("--tasks", default=None, help="comma-separated subset of tasks")
    _observation.add_arguments(parser)


_split = _observation.split


def run(args: argparse.Namespace) -> int:
    """Run ``python -m sandbox data`` with the parsed ``args``; return the exit status."""
    if args.data_command == "summary":
        return _summary(args)
    if args.data_command == "cache":
        return _cache(args)
    if args.data_command == "export":
        return _export(args)
    return _check_filter(args)


def _cache(args: argparse.Namespace) -> int:
    from sandbox.data.cache import TrialCache

    cache = TrialCache()
    if args.clear:
        print(f"{cache.folder}: {cache.clear()} cached trials deleted")
        return 0
    n, size = cache.size()
    print(f"{cache.folder}: {n} cached trials, {size / 2**20:.1f} MiB "
          "(safe to delete; --clear empties it, --no-cache bypasses it)")
    return 0


def _summary(args: argparse.Namespace) -> int:
    import warnings

    from sandbox.data.datasets import summarize
    from sandbox.data.recorded import SkippedTrialWarning, count_trials, load_recorded
    from sandbox.data.spec_frame import frame_yaml, suggest_for
    from sandbox.eval.progress import bar

    spec = _observation.data_spec(args)
    observe = _observation.observe(args, spec)
    with warnings.catch_warnings(), \
            bar(count_trials(args.data, _split(args.tasks), spec) or 0, "loading",
                not args.no_progress) as shown:
        warnings.simplefilter("ignore", SkippedTrialWarning)  # listed in the summary instead
        demos, skipped = load_recorded(args.data, tasks=_split(args.tasks), spec=spec,
                                       observe=observe, preprocess="causal",
                                       on_trial=shown.update)
    if not demos:
        messages = [f"skipped {f}: {r}" for f, r in skipped]
        _skipped.report(messages, args.verbose, 0)
        if not args.verbose:
            for reason, n in _reasons(skipped):
                print(f"skipped {n} trial{'s' if n > 1 else ''}: {reason}", file=sys.stderr)
        raise _skipped.no_usable(str(args.data), messages, "trial", args.verbose)
    result = {"data": str(args.data), "observe": list(observe), **summarize(demos, skipped)}
    result["realism"] = _realism(args, spec) if "hand" in observe else None
    frame = suggest_for(demos, spec)
    result["frame_suggestion"] = None if frame is None else frame.to_dict()
    from sandbox.data.noisefloor import floor_summary, format_floors  # issue 28 item 4

    result["noise_floor"] = floor_summary(demos)
    result["robot_space"] = spec.robot_space
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        print("\n".join([format_summary(result), *format_floors(result["noise_floor"])]))
        if frame is not None:
            print("\nSuggested placement (the demos' mean meeting point on Baxter's demonstrated "
                  "one, their reach turned toward the robot; paste into the spec):\n"
                  + frame_yaml(frame))
    return 0


def _reasons(skipped: list[tuple[str, str]]) -> list[tuple[str, int]]:
    """Each distinct skip reason (its first line) with the number of trials, most first."""
    from collections import Counter

    return Counter(" ".join(r.split()) for _, r in skipped).most_common()


def _export(args: argparse.Namespace) -> int:
    import warnings

    import sandbox.envs
    from sandbox.data.datasets import load_dataset
    from sandbox.data.minari_io import require_minari
    from sandbox.data.recorded import SkippedTrialWarning
    from sandbox.episodes.minari_export import default_env_id, export_demonstrations

    minari = require_minari()
    env_id = args.env_id or default_env_id(args.data)
    if env_id not in sandbox.envs.ENV_IDS + sandbox.envs.LEGACY_IDS:
        raise ValueError(f"--env-id: expected one of {sandbox.envs.ENV_IDS}, got {env_id!r}")
    spec = _observation.data_spec(args)
    if spec.robot_space == "task":      # the datasets' actions are the environments' joints
        raise ValueError("--spec: expected a joint-space robot part for a Minari dataset (its "
                         "actions are Baxter's joint targets), got robot.space task")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", SkippedTrialWarning)
        demos = load_dataset(args.data, spec=spec, observe=_observation.observe(args, spec),
                             seed=args.seed, tasks=_split(args.tasks),
                             n_per_task=args.n_per_task, preprocess=args.preprocess)
    if not demos:
        from sandbox.data.skipped import no_usable

        raise no_usable(f"--data {args.data}", [str(w.message) for w in caught],
                        "demonstration")
    dataset = export_demonstrations(demos, args.minari_id, env_id=env_id,
                                    preprocess=args.preprocess, data=str(args.data),
                                    force=args.force)
    from minari.storage import get_dataset_path

    tasks = sorted({d.task for d in demos})
    print(f"wrote {dataset.total_episodes} episodes ({dataset.total_steps} steps) of "
          f"{len(tasks)} tasks {tasks} to the Minari dataset {args.minari_id} "
          f"({get_dataset_path(args.minari_id)}), environment {env_id}, "
          f"{len(caught)} trials skipped; minari {minari.__version__}")
    return 0


def _realism(args: argparse.Namespace, spec: Any) -> dict | None:
    """Synthetic vs recorded statistics of the hand, if the synthetic package offers them."""
    if args.synthetic == "none" or spec.modalities["hand"].size != 3:
        return None
    try:
        import numpy as np

        from sandbox.data.synthetic import DATASETS, compare_realism, make_dataset
    except ImportError:
        return None
    if args.synthetic not in DATASETS:
        raise ValueError(f"--synthetic: expected one of {[*DATASETS, 'none']}, "
                         f"got {args.synthetic!r}")
    import warnings

    from sandbox.data.recorded import load_recorded

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        raw, _ = load_recorded(args.data, tasks=_split(args.tasks), spec=spec, observe="hand",
                               preprocess="none")
    synthetic = make_dataset(args.synthetic, 20, np.random.default_rng(0))
    return {"synthetic": f"synthetic:{args.synthetic}", "seed": 0, "n_per_task": 20,
            "table": compare_realism(synthetic, raw)}


def format_summary(result: dict[str, Any]) -> str:
    """The summary dict as readable text."""
    lines = [f"Dataset {result['data']}: {result['all']['trials']} trials in "
             f"{len(result['tasks'])} tasks ({len(result['skipped'])} skipped)", ""]
    lines.append(f"{'task':<20}{'trials':>7}  {'duration mean [min, max] (s)':<30}"
                 f"{'rows/s':>8}{'frames/s':>10}")
    for task, r in [*result["tasks"].items(), ("all", result["all"])]:
        span = f"{r['duration_mean_s']:.2f} [{r['duration_min_s']:.2f}, {r['duration_max_s']:.2f}]"
        lines.append(f"{task:<20}{r['trials']:>7}  {span:<30}"
                     f"{r['rows_per_s']:>8.1f}{r['frames_per_s']:>10.1f}")
    rates = ", ".join(f"{name} {r['samples_per_s']:.1f}"
                      for name, r in result.get("modalities", {}).items())
    if rates:
        lines += ["", f"New samples per second, by modality: {rates}"]
    g = result["glitches"]
    lines += ["", f"Tracker glitches over {g['rows']} rows (trials showing it):"]
    labels = [
        ("repeated_timestamps", "rows repeating the previous time stamp"),
        ("stale_rows", "rows re-sending a frame already received"),
        ("jumps", "jumps >= 5 cm between consecutive frames"),
        ("excursions", "frames > 4 cm off their running median"),
        ("zero_rows", "(0, 0, 0) rows (person lost)"),
        ("missing_rows", "rows with a missing human value"),
        ("gate_rejected", "frames rejected by the causal filter's gate"),
        ("filter_resets", "filter re-initialisations"),
    ]
    for key, label in labels:
        v = g[key]
        lines.append(f"  {label:<46}{int(v['total']):>7} ({100 * v['fraction_of_rows']:5.2f} %)"
                     f"  in {v['trials']} trials")
    fs = g["frozen_segments"]
    lines.append(f"  {'frozen skeletons (> 0.25 s without a new frame)':<46}"
                 f"{int(fs['total']):>7} stretches, {g['frozen_s']['total']:.2f} s"
                 f"  in {fs['trials']} trials")
    dropped = ", ".join(f"{n} ({why})" for why, n in g["rows_dropped"].items()) or "none"
    lines += [f"  rows dropped: {dropped}", ""]
    lines.append("Skipped trials: " + ("none" if not result["skipped"] else ""))
    lines += [f"  {s['file']}: {' '.join(s['reason'].split())}" for s in result["skipped"]]
    if result.get("realism"):
        from sandbox.data.synthetic.realism import format_realism

        r = result["realism"]
        lines += ["", f"Realism: {r['synthetic']} ({r['n_per_task']} per task, seed "
                      f"{r['seed']}) vs these recordings (medians)", format_realism(r["table"])]
    return "\n".join(lines)


def _points(dims: tuple[str, ...]) -> list[tuple[str, ...]]:
    """A position modality's 3-D points (one track if its size is not a multiple of 3)."""
    width = 3 if len(dims) % 3 == 0 else len(dims)
    return [dims[i:i + width] for i in range(0, len(dims), width)]


def _filter_table(path, spec, modalities):
    """The trial's table (time in s, positions in m in the spec's frame, cut as the spec
    says) if ``check-filter`` can use it: readable, at least 3 rows, times finite, never
    going backwards and plausible (:func:`sandbox.core.limits.check_duration`); else None."""
    import numpy as np

    from sandbox.data.limits import check_duration
    from sandbox.data.recorded import TrialError
    from sandbox.data.spec_read import cut_rows, read_spec_table

    try:
        table, extra, _ = read_spec_table(path, spec, modalities, lambda column: "")
        t = table[:, 0]
        ok = np.isfinite(t) & np.r_[True, np.diff(t) >= 0]
        if ok.sum() < 3 or not ok.all():
            return None
        table, _ = cut_rows(spec, table, extra, sum(m.size for m in modalities))
        check_duration(np.unique(table[:, 0]))
    except (TrialError, ValueError):
        return None
    return table if table.shape[0] >= 3 else None


def _check_filter(args: argparse.Namespace) -> int:
    import numpy as np

    from sandbox.data.filtercheck import holdout_errors
    from sandbox.data.filtering import FilterConfig
    from sandbox.data.glitches import find_glitches
    from sandbox.data.recorded import trial_list

    settings = {"accel_std": args.accel_std, "noise_std": args.noise_std,
                "time_jitter_std": args.jitter_std, "gate_prob": args.gate_prob}
    config = FilterConfig(**{k: v for k, v in settings.items() if v is not None})
    spec = _observation.data_spec(args)
    points = [cols for m in spec.observed(_split(args.observe)) if m.kind == "position"
              for cols in _points(m.dims)]
    if not points:
        raise ValueError("--observe: check-filter needs a position modality (hand, arm)")
    mods = [m for m in spec.observed(_split(args.observe)) if m.kind == "position"]
    smooth, causal, frames, rejected, trials = [], [], 0, 0, 0
    for _, path in trial_list(args.data, _split(args.tasks), spec):
        table = _filter_table(path, spec, mods)
        if table is None:
            continue
        t = table[:, 0]
        start = 1
        for cols in points:
            human = table[:, start:start + len(cols)]
            start += len(cols)
            fresh = find_glitches(t, human).fresh
            s, c, counts = holdout_errors(t, np.where(fresh[:, None], human, np.nan), config)
            smooth.append(s)
            causal.append(c)
            frames += int(fresh.sum())
            rejected += counts["rejected"] + counts["reset"]
        trials += 1
    if not trials:
        raise ValueError(f"data: no usable trial in {args.data}")
    s, c = np.concatenate(smooth), np.concatenate(causal)
    result = {
        "data": str(args.data), "trials": trials, "config": config.__dict__,
        "hidden_frames": int(s.size),
        "smooth_error_mm": {"median": 1e3 * float(np.median(s)),
                            "rms": 1e3 * float(np.sqrt(np.mean(s**2)))},
        "causal_prediction_error_mm": {"median": 1e3 * float(np.median(c)),
                                       "rms": 1e3 * float(np.sqrt(np.mean(c**2)))},
        "frames": frames, "gate_rejected_fraction": rejected / frames,
    }
    if args.json:
        print(json.dumps(result, indent=2))
        return 0
    cfg = ", ".join(f"{k}={v:g}" for k, v in result["config"].items())
    print(f"Filter {cfg}\n{trials} trials, {s.size} hidden frames (every 3rd, first 60 %)")
    for key, label in (("smooth_error_mm", "RTS smoother"),
                       ("causal_prediction_error_mm", "causal prediction")):
        e = result[key]
        print(f"  {label:<18} error median {e['median']:.2f} mm, rms {e['rms']:.2f} mm")
    print(f"  gate rejections: {rejected} of {frames} frames "
          f"({100 * result['gate_rejected_fraction']:.2f} %)")
    sys.stdout.flush()
    return 0
