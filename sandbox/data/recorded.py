"""Recorded handovers in the per-trial CSV layout ``<root>/<task>/<trial>.csv``.

One file per demonstration, one row per sample, a header row naming the
columns (see ``data/README.md`` of the shared recordings). A
:class:`~sandbox.data.spec.DataSpec` says which columns are the time, the
robot (rad) and each observation modality; ``observe`` chooses the
modalities to load (default: the hand ``human_left_hand_x/y/z``, m, as in
the paper; the built-ins add ``arm``, the same side's elbow and shoulder, and
``emg``, the 8 Myo channels).

What the loader does with a trial (everything it does is counted in
``demo.meta["report"]``, see :func:`load_trial`):

0. The spec's layout (:mod:`sandbox.data.spec_read`): the trial's files are
   read and joined, the time made (``rate_hz``) or converted, positions
   converted to metres (``units``) and moved to the robot's base frame
   (``frame``); after step 1, the rows are cut to the handover (``segment``,
   times restarting at 0) and thinned (``resample_hz``).
1. Rows without a time or with a missing robot value are dropped, rows whose
   time goes backwards are dropped. Missing human values stay NaN.
2. Rows that share their time stamp with the previous row (about 40 % of the
   recorded rows) are collapsed to the last row of each time stamp, so times
   are strictly increasing. The first and last time stamps are kept: the
   ground-truth duration is the recorded span.
3. Each modality is preprocessed by its kind (:mod:`sandbox.data.preprocess`):
   tracked positions are classified (zero rows, re-sent frames, freezes,
   jumps) and filtered (``"causal"`` for test streams, ``"smooth"`` for
   training); signals are rectified and low-pass filtered into an envelope.
4. A trial in which an observed modality has fewer than two valid samples,
   or a signal that never changes, is skipped with the reason.

Reading the file and the limits it must respect (:mod:`sandbox.data.limits`:
file, line, field and row counts, the time span and unit, value magnitudes,
Baxter's joint limits) are in :mod:`sandbox.data.trialfile`; a file beyond
them is skipped with the reason, like any other unusable trial.

``demo.meta["modality_measured"]`` (bool, shape (T, n_modalities)) marks the
rows that carry a new, accepted sample of each modality; ``meta["human_measured"]``
(T,) those of any.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from functools import partial
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np

from sandbox.core.modality import Modality
from sandbox.data.cache import TrialCache, resolve_cache
from sandbox.data.demonstration import Demonstration
from sandbox.data.limits import MAX_DURATION_S
from sandbox.data.preprocess import (  # noqa: F401 - preprocess_rows/_demonstration re-exported
    PREPROCESS,
    check_options,
    measured_meta,
    preprocess_demonstration,
    preprocess_human,
    preprocess_rows,
    summary_counts,
)
from sandbox.data.spec import HAND, ROBOT_COLUMNS, TIME_COLUMN, DataSpec  # noqa: F401
from sandbox.data.spec_read import (  # noqa: F401 - find_trials, count_trials re-exported
    count_trials,
    cut_rows,
    find_trials,
    layout_trials,
    part_files,
    read_spec_table,
    trial_list,
)
from sandbox.data.trialfile import (  # noqa: F401 - re-exported: the loader's public names
    HUMAN_COLUMNS,
    Columns,
    TrialError,
    _fix,
    check_plausible,
    read_trial_table,
)
from sandbox.validation import FloatArray, check_positive


class SkippedTrialWarning(UserWarning):
    """Issued for each trial :func:`load_recorded` skips."""


def _usable_rows(table: FloatArray, n_human: int) -> tuple[np.ndarray, dict[str, int]]:
    """Mask of rows to keep and the number of rows dropped per reason."""
    t, robot = table[:, 0], table[:, 1 + n_human :]
    no_time = np.isnan(t)
    no_robot = ~no_time & np.isnan(robot).any(axis=1)
    keep = ~no_time & ~no_robot
    running = np.maximum.accumulate(np.where(keep, t, -np.inf))
    backwards = keep & (t < np.r_[-np.inf, running[:-1]])
    keep &= ~backwards
    dropped = {"time missing": int(no_time.sum()), "robot value missing": int(no_robot.sum()),
               "time going backwards": int(backwards.sum())}
    return keep, {k: v for k, v in dropped.items() if v}


def load_trial(
    path: str | Path,
    *,
    task: str | None = None,
    spec: DataSpec | None = None,
    observe: Sequence[str] | str | None = None,
    columns: Columns | None = None,
    preprocess: str = "smooth",
    max_duration: float = MAX_DURATION_S,
    cache: TrialCache | bool | str | Path | None = None,
    **options: Any,
) -> Demonstration:
    """Load one trial file as a :class:`Demonstration`.

    Parameters
    ----------
    path : str or Path
        The CSV file (a trial folder with the spec's ``files``).
    task : str, optional
        Task label; defaults to the name of the file's folder.
    spec : DataSpec, optional
        What the columns are (default: the built-in layout of the recorded set).
    observe : sequence of str or str, optional
        Modalities to load, e.g. ``["hand", "arm", "emg"]`` or ``"hand,arm"``
        (default: the spec's, ``hand``).
    columns : Columns, optional
        Shorthand for a hand-only spec with these columns (instead of ``spec``).
    preprocess : {"none", "causal", "smooth"}
        What to do with the human samples (:mod:`sandbox.data.preprocess`).
    max_duration : float
        Longest time span (s) accepted (default
        :data:`sandbox.core.limits.MAX_DURATION_S`, 60 s); a longer trial, or
        one sampled faster than 10 kHz, is refused with a hint at the unit its
        times look like.
    **options
        Preprocessing options (:data:`sandbox.data.preprocess.DEFAULTS`):
        ``config`` (:class:`FilterConfig`), ``freeze_s`` (a stretch without a
        new tracker frame longer than this, s, is a frozen skeleton),
        ``max_fill_s`` ("smooth" bridges gaps between accepted frames up to
        this long, s), ``jump_m`` (a step between consecutive frames of at
        least this, m, is a jump), ``excursion_m`` ("smooth" sets aside frames
        farther than this, m, from their running median; 0 disables; on the
        recorded handovers 4 cm sets aside 4.9 % of the frames; on synthetic
        tracks with known truth it finds 67 % of the frames more than 3 cm off,
        with 96 % precision), ``signal_cutoff_hz`` and ``signal_rate_hz``
        (the envelope of signals, :mod:`sandbox.data.signals`; 5 Hz and 30 Hz by default).
    cache : TrialCache, bool or path, optional
        Keep the result on disk and reuse it when the same file is loaded the
        same way again (:mod:`sandbox.data.cache`): ``True`` the user's cache
        folder, a path a folder of your own; default none.

    Returns
    -------
    Demonstration
        ``source`` is the file path, ``modalities`` the observed ones;
        ``meta["report"]`` is a JSON-ready dict of what was found and done;
        ``meta["modality_measured"]`` and ``meta["human_measured"]`` mark the
        rows carrying an accepted new sample.

    Raises
    ------
    ValueError
        (:class:`TrialError`) the file cannot be used; the message says why and
        names the file (a missing column: also the option that fixes it). The
        limits of :mod:`sandbox.data.limits` apply: file, line, field and row
        counts, the time span and unit, value magnitudes and, for columns named
        after Baxter's joints, the URDF joint limits.
    """
    # Over 60 lines only by this docstring (nine documented parameters); the body is steps.
    check_options(preprocess, **options)
    max_duration = check_positive(max_duration, "max_duration")
    spec = _spec(spec, columns)
    modalities = spec.observed(observe)
    path = _path(path, "path")
    task = task or path.parent.name
    store = resolve_cache(cache)
    members = part_files(path, spec) if spec.layout.files else None
    key = None if store is None else store.key(
        path, members, task=task, spec=spec.to_dict(), observe=[m.name for m in modalities],
        preprocess=preprocess, max_duration=max_duration, options=options)
    if key is None:               # no cache, or not a regular file within the limits
        store, key = None, ""
    found = _cached(store, key, path)
    if found is not None:
        return found
    return _load_and_keep(store, key, path, task, spec, modalities, preprocess, max_duration,
                          options)


def _cached(store: TrialCache | None, key: str, path: Path) -> Demonstration | None:
    """The trial the cache holds under ``key`` (None if none); a cached refusal is raised."""
    found = None if store is None else store.get(key, path)
    if isinstance(found, str):
        raise TrialError(f"{path}: {found}")
    return found


def _load_and_keep(store: TrialCache | None, key: str, path: Path, task: str, spec: DataSpec,
                   modalities, preprocess: str, max_duration: float,
                   options: dict) -> Demonstration:
    """Load the trial; keep it, or why it was refused, in the cache (if any)."""
    try:
        demo = _load_trial(path, task, spec, modalities, preprocess, max_duration, options)
    except TrialError as error:
        if store is not None:
            store.put(key, str(error), path)
        raise TrialError(f"{path}: {error}") from None
    if store is not None:
        store.put(key, demo, path)
    return demo


def _path(value: Any, name: str) -> Path:
    if not isinstance(value, (str, PathLike)):
        raise ValueError(f"{name}: expected a path, got {value!r}")
    return Path(value)


def _spec(spec: DataSpec | None, columns: Columns | None) -> DataSpec:
    if spec is not None and columns is not None:
        raise ValueError("spec and columns: expected one of them, got both")
    if columns is not None:
        if not isinstance(columns, Columns):
            raise ValueError(f"columns: expected a Columns, got {type(columns).__name__}")
        return columns.as_spec()
    if spec is not None and not isinstance(spec, DataSpec):
        raise ValueError(f"spec: expected a DataSpec, got {type(spec).__name__}")
    return spec or DataSpec()


def _load_trial(path: Path, task: str, spec: DataSpec, modalities: Sequence[Modality],
                preprocess: str, max_duration: float, options: dict[str, Any]) -> Demonstration:
    columns = _named(Columns.from_spec(spec, modalities), spec)
    owners = {c: m.name for m in modalities for c in m.dims}
    fix = partial(_fix, columns=columns, owners=owners)
    table, extra, notes = read_spec_table(path, spec, modalities, fix)
    n_rows = table.shape[0]
    p = len(columns.human)
    keep, dropped = _usable_rows(table, p)
    if notes["truncated_last_row"]:
        dropped["truncated last row"] = 1
    if notes.get("unequal_files"):
        dropped["files of unequal length"] = int(notes["unequal_files"])
    n_kept = int(keep.sum())
    table, cut = cut_rows(spec, table[keep], extra[keep], p)
    n_rows -= n_kept - table.shape[0]                # rows left out by segment/resample_hz
    times, human, robot = table[:, 0], table[:, 1 : 1 + p], table[:, 1 + p :]
    last = np.flatnonzero(np.r_[np.diff(times) > 0, True]) if times.size else times.astype(int)
    if last.size < 2:
        why = "; ".join(f"{v} dropped ({k})" for k, v in dropped.items())
        raise TrialError(
            f"only {last.size} usable time stamp(s) out of {n_rows} rows, need at least 2"
            + (f" ({why})" if why else "")
        )
    check_plausible(times[last], human, robot, columns, max_duration)
    out, measured, counts = preprocess_human(
        times, human, modalities, preprocess,
        signal_filters={m.name: spec.layout.signal_filter(m.name) for m in modalities},
        **options)
    _check_usable(modalities, measured, counts)
    report = {
        "file": str(path), "task": task, "preprocess": preprocess, "rows": n_rows,
        "rows_dropped": dropped, "repeated_timestamps": int(times.size - last.size),
        "samples": int(last.size), "duration_s": float(times[-1] - times[0]), **cut,
        **summary_counts(counts, modalities),
    }
    return Demonstration(
        times=times[last], human=out, robot=robot[last], task=task, modalities=modalities,
        robot_names=columns.robot, source=str(path), robot_space=spec.robot_space,
        meta={"report": report, **measured_meta(measured)},
    )


def _named(columns: Columns, spec: DataSpec) -> Columns:
    """With ``files``: the robot columns without their ``part.`` (the joints' own names, for
    their limits and the model), unless two parts share a name."""
    if not spec.layout.files:
        return columns
    bare = tuple(c.partition(".")[2] for c in columns.robot)
    if len(set(bare)) < len(bare) or set(bare) & {*columns.human, columns.time}:
        return columns
    return Columns(columns.human, bare, columns.time)


def _check_usable(modalities, measured, counts) -> None:
    """Every observed modality needs two valid samples; a signal must change."""
    for i, m in enumerate(modalities):
        c = counts[m.name]
        if m.kind == "signal" and c.get("signal_constant"):
            raise TrialError(f"modality {m.name!r} is constant or missing in this trial "
                             f"({c['signal_fresh_rows']} new samples): no signal to use")
        if measured[:, i].sum() < 2:
            if m.kind == "position":
                raise TrialError(
                    f"fewer than 2 valid samples of {m.name!r} ({c['missing_rows']} rows "
                    f"missing, {c['zero_rows']} rows (0, 0, 0), {c['stale_rows']} repeated)")
            raise TrialError(f"fewer than 2 valid samples of {m.name!r}")


def load_recorded(
    root: str | Path,
    *,
    tasks: Sequence[str] | None = None,
    spec: DataSpec | None = None,
    observe: Sequence[str] | str | None = None,
    columns: Columns | None = None,
    preprocess: str = "smooth",
    max_duration: float = MAX_DURATION_S,
    cache: TrialCache | bool | str | Path | None = None,
    on_trial: Callable[[], Any] | None = None,
    **options: Any,
) -> tuple[list[Demonstration], list[tuple[str, str]]]:
    """Load every trial of ``<root>/<task>/<trial>.csv`` (optionally only ``tasks``).

    Parameters
    ----------
    root : str or Path
        The dataset folder.
    tasks : sequence of str, optional
        Tasks to load (folder names); default all.
    spec, observe, columns, preprocess, max_duration, cache, **options
        As in :func:`load_trial`.
    on_trial : callable, optional
        Called with no argument after each file, loaded or skipped (e.g. a
        progress bar's ``update``).

    Returns
    -------
    demos : list of Demonstration
        In task then file order.
    skipped : list of (str, str)
        ``(file, reason)`` of every trial that could not be used; each also
        raises a :class:`SkippedTrialWarning`. Whatever goes wrong with one
        file skips that file only: an error other than :class:`TrialError`
        (a bug) is listed with its type.
    """
    check_options(preprocess, **options)
    check_positive(max_duration, "max_duration")
    spec = _spec(spec, columns)
    spec.observed(observe)
    store = resolve_cache(cache)
    demos: list[Demonstration] = []
    trials, skipped = layout_trials(root, tasks, spec)
    for file, reason in skipped:
        warnings.warn(f"skipped {file}: {reason}", SkippedTrialWarning, stacklevel=2)
    for task, path in trials:
        try:
            demos.append(load_trial(path, task=task, spec=spec, observe=observe,
                                    preprocess=preprocess, max_duration=max_duration,
                                    cache=store, **options))
        except Exception as error:  # noqa: BLE001 - one file never stops the others
            reason = str(error).removeprefix(f"{path}: ")
            if not isinstance(error, TrialError):
                reason = f"unexpected {type(error).__name__}: {reason}"
            skipped.append((str(path), reason))
            warnings.warn(f"skipped {path}: {reason}", SkippedTrialWarning, stacklevel=2)
        if on_trial is not None:
            on_trial()
    return demos, skipped
