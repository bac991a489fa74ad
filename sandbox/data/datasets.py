"""One entry point for demonstrations: a recorded folder or a named synthetic set.

``data`` is either a folder in the per-trial CSV layout ``<root>/<task>/<trial>.csv``
(:mod:`sandbox.data.recorded`; a :class:`~sandbox.data.spec.DataSpec` says what
its columns are, ``observe`` which modalities to load) or ``synthetic:NAME``
with NAME one of :data:`sandbox.data.synthetic.DATASETS` (generated, seeded,
needs nothing on disk; it observes the hand, the arm or both, no EMG).

Preprocessing defaults: ``"smooth"`` (RTS-smoothed human track, short gaps
filled) because datasets are mostly used to *train*. Streams a predictor is
tested on should be preprocessed causally: pass ``preprocess="causal"`` (only
samples received so far shape each value) or ``"none"`` and filter online with
:class:`sandbox.data.filtering.HandFilter`.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from sandbox.data.demonstration import Demonstration, stack_tasks
from sandbox.data.limits import MAX_GRID_SAMPLES, MAX_RATE_HZ
from sandbox.data.spec import DataSpec, resolve
from sandbox.validation import check_array, check_choice, check_integer, check_positive, short_text

SYNTHETIC_PREFIX = "synthetic:"
#: Prefix of a synthetic out-of-distribution set (:mod:`sandbox.data.synthetic.ood`).
SYNTHETIC_OOD_PREFIX = "synthetic-ood:"
#: Prefix of a Minari dataset id (:mod:`sandbox.data.minari_io`, optional extra).
MINARI_PREFIX = "minari:"
#: Demonstrations per task of a synthetic set when ``n_per_task`` is not given.
DEFAULT_SYNTHETIC_PER_TASK = 20
#: Most demonstrations per task ``n_per_task`` accepts (a synthetic set generates them all).
MAX_SYNTHETIC_PER_TASK = 10_000
PREPROCESS = ("none", "causal", "smooth")


def synthetic_names() -> tuple[str, ...]:
    """Names accepted after ``synthetic:`` (empty if the generator is unavailable)."""
    try:
        from sandbox.data.synthetic import DATASETS
    except ImportError:  # pragma: no cover - the synthetic package ships with sandbox
        return ()
    return tuple(DATASETS)


def _spec_options() -> str:
    names = ", ".join(f"synthetic:{n}" for n in synthetic_names())
    return (f"a folder <root>/<task>/<trial>.csv, minari:ID, synthetic-ood:FAMILY or one of "
            f"[{names}]")


def load_dataset(
    data: str | Path,
    *,
    spec: DataSpec | str | Path | None = None,
    observe: Sequence[str] | str | None = None,
    seed: int = 0,
    tasks: Sequence[str] | None = None,
    n_per_task: int | None = None,
    preprocess: str = "smooth",
    rate_hz: float | None = None,
    cache: Any = None,
    on_trial: Any = None,
    session: int | None = None,
    **options: Any,
) -> list[Demonstration]:
    """Load or generate demonstrations.

    Parameters
    ----------
    data : str or Path
        A dataset folder, ``"synthetic:NAME"``, ``"synthetic-ood:FAMILY[@BASE]"``
        (:mod:`sandbox.data.synthetic.ood`), or ``"minari:ID"``: a Minari
        dataset written by ``python -m sandbox data export`` (optional extra,
        :mod:`sandbox.data.minari_io`; stored preprocessed, so ``preprocess`` must be
        the export's).
    spec : DataSpec or path, optional
        What a folder's columns are (a :class:`~sandbox.data.spec.DataSpec` or a
        spec file); default the built-in layout of the recorded Baxter set.
    observe : sequence of str or str, optional
        Modalities to load (default the spec's: ``hand``); synthetic sets carry
        ``hand`` and ``arm`` (e.g. ``"hand,arm"``), no ``emg``.
    seed : int
        Seed (>= 0) of the synthetic generator (``np.random.default_rng(seed)``);
        unused for folders.
    tasks : sequence of str, optional
        Keep only these tasks (default all); an unknown task is a ``ValueError``
        listing the available ones.
    n_per_task : int, optional
        Demonstrations per task, 1 to :data:`MAX_SYNTHETIC_PER_TASK`: for a
        folder the first ``n_per_task`` trials of each task in file order (all
        if None); for a synthetic set the number generated (default
        :data:`DEFAULT_SYNTHETIC_PER_TASK`).
    preprocess : {"none", "causal", "smooth"}
        Human-track preprocessing (see :mod:`sandbox.data.recorded`); applied to
        synthetic sets too, whose tracker artefacts mimic the recordings.
    rate_hz : float, optional
        Resample every demonstration on a uniform grid at this rate
        (:func:`resample_uniform`); default: keep the sample times.
    session : int, optional
        Synthetic sets only: the recording session (>= 0,
        :func:`sandbox.data.synthetic.session.draw_session`: tracker frame,
        meeting offset, tempo, the motion's tail); None: today's data. A
        session with a folder or ``minari:ID`` is a ``ValueError``.
    **options
        Passed to the loader / preprocessing: ``columns`` and ``max_duration``
        (folders only, :func:`sandbox.data.recorded.load_trial`), and those of
        :data:`sandbox.data.preprocess.DEFAULTS`.

    Returns
    -------
    list of Demonstration
        Grouped by task. Trials that cannot be used are skipped with a
        :class:`sandbox.data.recorded.SkippedTrialWarning`.
    """
    # Over 60 lines only by this docstring (its parameters); the body is steps.
    tasks = _check_selection(preprocess, seed, n_per_task, tasks)
    if session is not None:
        options = {**options, "session": _check_session(data, session)}
    demos = _load(data, resolve(spec), spec is not None, observe, seed, tasks, n_per_task,
                  preprocess, {"cache": cache, "on_trial": on_trial}, options)
    if rate_hz is not None:
        demos = [resample_uniform(d, rate_hz) for d in demos]
    return demos


def _check_selection(preprocess: str, seed: int, n_per_task: int | None,
                     tasks: Sequence[str] | None) -> list[str] | None:
    """``ValueError`` unless the options are valid; returns ``tasks`` as a list (or None)."""
    check_choice(preprocess, "preprocess", PREPROCESS)
    check_integer(seed, "seed", 0)
    if n_per_task is not None:
        check_integer(n_per_task, "n_per_task", 1, MAX_SYNTHETIC_PER_TASK)
    if tasks is not None:
        if isinstance(tasks, (str, bytes)) or not isinstance(tasks, Iterable):
            raise ValueError(f"tasks: expected a list of task names, got {tasks!r}")
        tasks = list(tasks)
    return tasks


def _check_session(data: str | Path, session: Any) -> int:
    """``session`` as an int >= 0; ``ValueError`` unless ``data`` is ``synthetic:NAME``."""
    if not (isinstance(data, str) and data.startswith(SYNTHETIC_PREFIX)):
        raise ValueError(f"session: only for synthetic:NAME data (a recorded set is one "
                         f"session already), got a session with {str(data)!r}")
    return check_integer(session, "session", 0)


def _load(data: str | Path, layout: DataSpec, spec_given: bool, observe, seed: int,
          tasks: list[str] | None, n_per_task: int | None, preprocess: str, folder: dict,
          options: dict) -> list[Demonstration]:
    """The demonstrations of a synthetic set, a Minari dataset or a folder (``folder``:
    the folder-only ``cache`` and ``on_trial``)."""
    for prefix in (SYNTHETIC_PREFIX, SYNTHETIC_OOD_PREFIX):
        if isinstance(data, str) and data.startswith(prefix):
            observed = [m.name for m in layout.observed(observe)]
            return _synthetic(data[len(prefix):], seed, tasks, n_per_task, preprocess,
                              {"observe": observed, **options}, ood=prefix != SYNTHETIC_PREFIX)
    if isinstance(data, str) and data.startswith(MINARI_PREFIX):
        return _minari(data[len(MINARI_PREFIX):], layout, observe, tasks, n_per_task,
                       preprocess, options)
    if isinstance(data, (str, Path)) and _is_folder(data):
        given = {"observe": observe, **folder, **options}
        if "columns" not in options:          # columns= is shorthand for a hand-only spec
            given["spec"] = layout
        elif spec_given:
            raise ValueError("spec and columns: expected one of them, got both")
        return _recorded(Path(data), tasks, n_per_task, preprocess, given)
    raise ValueError(f"data: expected {_spec_options()}, got {short_text(str(data))}")


def _is_folder(data: str | Path) -> bool:
    """Whether ``data`` names an existing folder (False for a name the system refuses)."""
    try:
        return Path(data).is_dir()
    except (OSError, ValueError):
        return False



def _recorded(root, tasks, n_per_task, preprocess, options) -> list[Demonstration]:
    from sandbox.data.recorded import load_recorded

    demos, _ = load_recorded(root, tasks=tasks, preprocess=preprocess, **options)
    if n_per_task is None:
        return demos
    return [d for group in stack_tasks(demos).values() for d in group[: int(n_per_task)]]


def _minari(dataset_id, layout, observe, tasks, n_per_task, preprocess, options):
    """A Minari dataset written by ``python -m sandbox data export``."""
    from sandbox.data.minari_io import load_for_fit
    from sandbox.limits import MAX_NAME_CHARS

    if len(dataset_id) > MAX_NAME_CHARS:
        raise ValueError(f"data: expected minari:ID with an ID of at most {MAX_NAME_CHARS} "
                         f"characters (sandbox.limits.MAX_NAME_CHARS), got "
                         f"{short_text(dataset_id)}")
    if options:
        raise ValueError(f"{sorted(options)}: only used for recorded folders, not minari:ID")
    return load_for_fit(dataset_id, [m.name for m in layout.observed(observe)], tasks=tasks,
                        n_per_task=n_per_task, preprocess=preprocess)


def _synthetic(name, seed, tasks, n_per_task, preprocess, options, *,
               ood: bool = False) -> list[Demonstration]:
    """A named synthetic set (``ood``: an out-of-distribution one, ``synthetic-ood:NAME``);
    ``options["observe"]``: its modalities (hand and/or arm)."""
    from sandbox.data.synthetic.observe import check_observe

    options = dict(options)
    observe = check_observe(options.pop("observe"))
    if not ood and name not in synthetic_names():
        raise ValueError(f"data: expected {_spec_options()}, got 'synthetic:{short_text(name)}'")
    for key in ("columns", "max_duration"):
        if key in options:
            raise ValueError(f"{key}: only used for recorded folders, not synthetic:NAME")
    n = DEFAULT_SYNTHETIC_PER_TASK if n_per_task is None else int(n_per_task)
    session = options.pop("session", None)
    demos = _generate(name, n, np.random.default_rng(seed), observe, session, ood)
    if tasks is not None:
        available = list(stack_tasks(demos))
        unknown = [t for t in tasks if t not in available]
        if unknown:
            raise ValueError(f"tasks: expected some of {available}, got unknown {unknown}")
        demos = [d for d in demos if d.task in set(tasks)]
    if preprocess == "none":
        return demos
    from sandbox.data.preprocess import preprocess_demonstration

    return [preprocess_demonstration(d, preprocess, **options) for d in demos]


def _generate(name: str, n: int, rng: np.random.Generator, observe, session,
              ood: bool) -> list[Demonstration]:
    """``make_dataset`` of ``synthetic:NAME``, or the OOD family of ``synthetic-ood:NAME``."""
    if not ood:
        from sandbox.data.synthetic import make_dataset

        return make_dataset(name, n, rng, observe=observe, session=session)
    from sandbox.data.synthetic.ood import ood_demos, parse_name

    family, base = parse_name(name)
    if session is not None:
        raise ValueError("session: expected none for synthetic-ood:NAME (its motions are "
                         "today's session's)")
    return ood_demos(family, n, rng, base=base, observe=observe)


def resample_uniform(
    demo: Demonstration, rate_hz: float, *, max_gap_s: float = 0.25
) -> Demonstration:
    """Resample a demonstration on a uniform time grid spanning its recorded span.

    The grid runs from ``times[0]`` to ``times[-1]`` (both kept, so the duration
    is unchanged) with ``round(duration * rate_hz) + 1`` equally spaced points
    (the step is the one nearest to ``1 / rate_hz`` that fits the span). The robot is
    linearly interpolated. The human is linearly interpolated between valid
    samples, but a grid time inside a gap of more than ``max_gap_s`` seconds
    between valid samples stays NaN (nothing is invented across long dropouts).

    Parameters
    ----------
    demo : Demonstration
        The demonstration.
    rate_hz : float
        Grid rate (Hz), at most :data:`sandbox.data.limits.MAX_RATE_HZ`; the
        grid has at most :data:`~sandbox.data.limits.MAX_GRID_SAMPLES` points.
    max_gap_s : float
        Longest gap (s) between valid human samples that is interpolated.

    Returns
    -------
    Demonstration
        With ``meta["resampled_hz"] = rate_hz``; ``meta["human_measured"]`` is
        dropped (the grid carries no raw samples).
    """
    if not isinstance(demo, Demonstration):
        raise ValueError(f"demo: expected a Demonstration, got {type(demo).__name__}")
    rate_hz = check_positive(rate_hz, "rate_hz")
    max_gap_s = check_positive(max_gap_s, "max_gap_s", allow_zero=True)
    if rate_hz > MAX_RATE_HZ:
        raise ValueError(f"rate_hz: expected at most {MAX_RATE_HZ:g} Hz "
                         f"(sandbox.data.limits.MAX_RATE_HZ), got {rate_hz:g}")
    n = int(round(demo.duration * rate_hz)) + 1
    if n > MAX_GRID_SAMPLES:
        raise ValueError(f"rate_hz: {rate_hz:g} Hz over {demo.duration:g} s gives {n} samples, "
                         f"expected at most {MAX_GRID_SAMPLES} (sandbox.data.limits."
                         "MAX_GRID_SAMPLES)")
    t = np.linspace(demo.times[0], demo.times[-1], max(n, 2))
    robot = np.column_stack([np.interp(t, demo.times, q) for q in demo.robot.T])
    human = np.column_stack([_interp_gaps(t, demo.times, y, max_gap_s) for y in demo.human.T])
    meta = {k: v for k, v in demo.meta.items() if k != "human_measured"}
    meta["resampled_hz"] = rate_hz
    return demo.replace(times=t, human=human, robot=robot, meta=meta)


def _interp_gaps(t_new, t, y, max_gap_s) -> np.ndarray:
    ok = np.isfinite(y)
    out = np.full(t_new.size, np.nan)
    if not ok.any():
        return out
    tv, yv = t[ok], y[ok]
    out[:] = np.interp(t_new, tv, yv)
    k = np.searchsorted(tv, t_new, side="right")
    inside = (k > 0) & (k < tv.size)
    gap = np.where(inside, tv[np.minimum(k, tv.size - 1)] - tv[np.maximum(k - 1, 0)], 0.0)
    exact = np.isin(t_new, tv)
    bad = (t_new < tv[0]) | (t_new > tv[-1]) | (inside & (gap > max_gap_s) & ~exact)
    out[bad] = np.nan
    return check_array(out, "human", 1, allow_nan=True)


def summarize(
    demos: Sequence[Demonstration], skipped: Sequence[tuple[str, str]] = ()
) -> dict[str, Any]:
    """Statistics of loaded recorded trials, from their ``meta["report"]`` (JSON-ready).

    Parameters
    ----------
    demos : sequence of Demonstration
        Trials loaded by :func:`sandbox.data.recorded.load_recorded` (any preprocessing;
        "causal" or "smooth" also give the filter's gate rejections).
    skipped : sequence of (str, str)
        ``(file, reason)`` of the trials that were skipped.

    Returns
    -------
    dict
        ``tasks``: per task the number of trials, duration mean/min/max (s),
        rows per second and distinct tracker frames per second; ``all``: the
        same over all trials; ``modalities``: new samples per second of each
        modality (after preprocessing); ``glitches``: totals of each glitch with the
        number of trials showing it; ``skipped``: the reasons.
    """
    reports = [d.meta.get("report") for d in demos]
    if not demos or any(r is None or "rows" not in r for r in reports):
        raise ValueError("demos: expected trials loaded from files (with meta['report'])")
    groups: dict[str, list[dict]] = {}
    for demo, report in zip(demos, reports, strict=True):
        groups.setdefault(demo.task, []).append(report)
    return {
        "tasks": {task: _rates(rs) for task, rs in groups.items()},
        "all": _rates(reports),
        "modalities": _modality_rates(reports),
        "glitches": _glitch_totals(reports),
        "skipped": [{"file": f, "reason": r} for f, r in skipped],
    }


def _modality_rates(reports: list[dict]) -> dict[str, dict[str, float]]:
    """New (accepted) samples per second of every modality, over all trials."""
    total = sum(r["duration_s"] for r in reports)
    names = dict.fromkeys(n for r in reports for n in r.get("modalities", {}))
    return {n: {"samples_per_s": sum(r["modalities"][n].get("measured_samples", 0)
                                     for r in reports if n in r.get("modalities", {})) / total}
            for n in names}


def _rates(reports: list[dict]) -> dict[str, float]:
    durations = np.array([r["duration_s"] for r in reports])
    total = float(durations.sum())
    return {
        "trials": len(reports),
        "duration_mean_s": float(durations.mean()),
        "duration_min_s": float(durations.min()),
        "duration_max_s": float(durations.max()),
        "rows_per_s": sum(r["rows"] for r in reports) / total,
        "frames_per_s": sum(r["new_frames"] for r in reports) / total,
    }


_GLITCHES = ("repeated_timestamps", "stale_rows", "jumps", "excursions", "zero_rows",
             "missing_rows", "frozen_segments", "frozen_s", "gate_rejected", "filter_resets")


def _glitch_totals(reports: list[dict]) -> dict[str, Any]:
    rows = sum(r["rows"] for r in reports)
    out: dict[str, Any] = {"rows": rows}
    for key in _GLITCHES:
        values = [r.get(key, 0) for r in reports]
        out[key] = {"total": round(float(sum(values)), 4), "fraction_of_rows": sum(values) / rows,
                    "trials": int(sum(v > 0 for v in values))}
    dropped: dict[str, int] = {}
    for r in reports:
        for reason, n in r.get("rows_dropped", {}).items():
            dropped[reason] = dropped.get(reason, 0) + int(n)
    out["rows_dropped"] = dropped
    out["preprocess"] = sorted({r.get("preprocess", "none") for r in reports})
    return out
