"""Realism check: robust statistics of human hand motions, synthetic vs recorded.

The same robust estimator is applied to both sets, because the raw recordings
have 30 Hz sample-and-hold steps, repeated rows and 5 cm+ tracker jumps:

1. rows that are not finite or are exactly (0, 0, 0) are dropped, and of rows
   sharing a timestamp the last one is kept;
2. the track is interpolated on a 100 Hz grid, then filtered by a running
   median over ``median_s`` (0.5 s: removes excursions shorter than ~0.25 s and
   leaves monotonic motion unchanged) and a running mean over ``mean_s``
   (0.15 s: removes the 30 Hz steps);
3. speeds are central differences of the filtered track.

Statistics per demonstration (all from ``human``, the hand x, y, z in m):

``duration`` (s)
    ``times[-1] - times[0]``.
``path_length`` (m)
    Length of the filtered track over the whole demonstration.
``peak_speed`` (m/s)
    Maximum filtered speed before the hand first arrives within 10 % of the
    start-to-end distance of its end point (the reach, not later tracker jumps).
``reach_time`` (s)
    Time of that arrival.
``end_spread``, ``start_spread`` (m)
    Distance of the end (start) point from the median end (start) point of the
    demonstrations of the same task; the end point is the median of the valid
    rows in the last 25 % of the demonstration, the start the median of the
    first 0.1 s.

Statistics of the arm (:func:`arm_realism_stats`, from the ``hand`` and ``arm``
modalities; elbow and shoulder tracks filtered like the hand's):

``elbow_path``, ``shoulder_path`` (m)
    Length of the filtered elbow (shoulder) track over the whole demonstration.
``elbow_hand`` (m)
    Median elbow-hand distance over the valid rows.
``shoulder_travel`` (m)
    Distance from the shoulder's start point to its end point (as above).
``shoulder_spread`` (m)
    Distance of the shoulder's start point from the median one of the
    demonstrations of the same task (where the human stands).
``upper_arm`` (m)
    Median shoulder-elbow distance over the valid rows (reported, not a
    realism target: the tracker's skeleton has a short upper arm).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from scipy.ndimage import median_filter, uniform_filter1d

from sandbox.data.demonstration import Demonstration
from sandbox.validation import FloatArray, check_array, check_positive

#: Statistics computed by :func:`realism_stats`, in report order.
STATISTICS = ("duration", "path_length", "peak_speed", "reach_time", "end_spread", "start_spread")
#: Statistics computed by :func:`arm_realism_stats`, in report order.
ARM_STATISTICS = ("elbow_path", "elbow_hand", "shoulder_path", "shoulder_travel",
                  "shoulder_spread", "upper_arm")
#: The arm statistics synthetic sets should match (``upper_arm`` is reported only).
ARM_TARGETS = ARM_STATISTICS[:5]


def valid_rows(times: FloatArray, human: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Drop non-finite and (0, 0, 0) rows; of rows sharing a timestamp keep the last.

    Parameters
    ----------
    times : ndarray, shape (T,)
        Non-decreasing sample times (s).
    human : ndarray, shape (T, 3)
        Hand positions (m); NaN marks a dropout.

    Returns
    -------
    times, human : ndarray, shapes (T',), (T', 3)
        The kept rows (T' <= T), strictly increasing times.
    """
    ok = np.isfinite(human).all(axis=1) & ~np.all(human == 0.0, axis=1)
    t, x = times[ok], human[ok]
    last = np.r_[np.diff(t) > 0, True] if t.size else np.zeros(0, dtype=bool)
    return t[last], x[last]


def smooth_track(
    times: FloatArray, human: FloatArray, *, median_s: float = 0.5, mean_s: float = 0.15
) -> tuple[FloatArray, FloatArray]:
    """Robustly filtered hand track on a 100 Hz grid (see the module docstring).

    Parameters
    ----------
    times : array_like, shape (T,)
        Non-decreasing sample times (s); repeated timestamps are allowed.
    human : array_like, shape (T, 3)
        Hand positions (m), possibly with NaN or (0, 0, 0) rows.
    median_s, mean_s : float
        Widths (s) of the running median and running mean.

    Returns
    -------
    grid : ndarray, shape (G,)
        Times (s), 0.01 s apart.
    track : ndarray, shape (G, 3)
        Filtered positions (m).
    """
    times = check_array(times, "times", 1)
    human = check_array(human, "human", 2, shape=(times.size, 3), allow_nan=True)
    t, x = valid_rows(times, human)
    if t.size < 2:
        raise ValueError(f"human: expected at least 2 valid rows, got {t.size}")
    grid = np.arange(t[0], t[-1] + 1e-9, 0.01)
    track = np.column_stack([np.interp(grid, t, x[:, j]) for j in range(3)])
    n_med = max(1, int(round(check_positive(median_s, "median_s") / 0.01)) | 1)
    n_mean = max(1, int(round(check_positive(mean_s, "mean_s") / 0.01)) | 1)
    track = median_filter(track, size=(n_med, 1), mode="nearest")
    return grid, uniform_filter1d(track, n_mean, axis=0, mode="nearest")


def end_points(times: FloatArray, human: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Robust start and end points (m), shapes (3,) and (3,).

    The start is the median of the valid rows in the first 0.1 s, the end the
    median of the valid rows in the last 25 % of the demonstration.
    """
    t, x = valid_rows(np.asarray(times, float), np.asarray(human, float))
    if t.size == 0:
        raise ValueError("human: expected at least one valid row, got none")
    head = t <= t[0] + 0.1
    tail = t >= t[0] + 0.75 * (t[-1] - t[0])
    return np.median(x[head], axis=0), np.median(x[tail], axis=0)


def track_stats(times: FloatArray, human: FloatArray) -> dict[str, float]:
    """Per-track statistics: duration, path_length, peak_speed, reach_time (see module doc).

    Parameters
    ----------
    times : array_like, shape (T,)
        Non-decreasing sample times (s).
    human : array_like, shape (T, 3)
        Hand positions (m).
    """
    grid, track = smooth_track(times, human)
    start, end = end_points(times, human)
    speed = np.linalg.norm(np.gradient(track, grid, axis=0), axis=1)
    near = np.linalg.norm(track - end, axis=1) <= 0.1 * np.linalg.norm(end - start)
    arrive = int(np.argmax(near)) if near.any() else grid.size - 1
    times = np.asarray(times, float)
    return {
        "duration": float(times[-1] - times[0]),
        "path_length": float(np.sum(np.linalg.norm(np.diff(track, axis=0), axis=1))),
        "peak_speed": float(speed[: arrive + 1].max()),
        "reach_time": float(grid[arrive] - times[0]),
    }


def _spread(points: FloatArray, tasks: Sequence[str]) -> FloatArray:
    """Distance (m) of each point from the median point of its task, shape (n,)."""
    tasks = np.asarray(tasks)
    out = np.empty(len(points))
    for task in np.unique(tasks):
        sel = tasks == task
        out[sel] = np.linalg.norm(points[sel] - np.median(points[sel], axis=0), axis=1)
    return out


def realism_stats(demos: Sequence[Demonstration]) -> dict[str, Any]:
    """Robust statistics of the human hand motions of a set of demonstrations.

    Parameters
    ----------
    demos : sequence of Demonstration
        At least one; their ``hand`` modality (or, without one, ``human``)
        must hold the hand x, y, z (m) (P = 3).

    Returns
    -------
    dict
        One array of shape (n,) per name in :data:`STATISTICS` (units in the
        module docstring), plus ``"median"``: a dict of their medians and
        ``"n"``: the number of demonstrations.
    """
    demos = list(demos)
    if not demos or not all(isinstance(d, Demonstration) for d in demos):
        raise ValueError("demos: expected a non-empty sequence of Demonstration")
    hands = [_modality(d, "hand") if "hand" in [m.name for m in d.modalities] else d.human
             for d in demos]
    if any(h.shape[1] != 3 for h in hands):
        raise ValueError("demos: expected human hand positions with P = 3 dims")
    rows = [track_stats(d.times, h) for d, h in zip(demos, hands, strict=True)]
    out: dict[str, Any] = {k: np.array([r[k] for r in rows]) for k in rows[0]}
    ends = np.array([end_points(d.times, h) for d, h in zip(demos, hands, strict=True)])
    tasks = [d.task for d in demos]
    out["end_spread"] = _spread(ends[:, 1], tasks)
    out["start_spread"] = _spread(ends[:, 0], tasks)
    return _with_medians(out, STATISTICS, len(demos))


def _with_medians(out: dict[str, Any], keys: Sequence[str], n: int) -> dict[str, Any]:
    """``out`` (one array per statistic) with ``"median"`` of each of ``keys`` and ``"n"``."""
    out["median"] = {k: float(np.median(out[k])) for k in keys}
    out["n"] = n
    return out


def _compare(synthetic, recorded, stats, keys: Sequence[str]) -> dict[str, dict[str, float]]:
    """Medians of ``keys`` side by side; ``stats`` computes them from demonstrations."""
    a = synthetic if isinstance(synthetic, Mapping) else stats(synthetic)
    b = recorded if isinstance(recorded, Mapping) else stats(recorded)
    return _table(a, b, keys)


def compare_realism(
    synthetic: Sequence[Demonstration] | Mapping[str, Any],
    recorded: Sequence[Demonstration] | Mapping[str, Any],
) -> dict[str, dict[str, float]]:
    """Synthetic vs recorded medians of each statistic.

    Parameters
    ----------
    synthetic, recorded : sequence of Demonstration or dict
        Demonstrations, or the output of :func:`realism_stats` for them.

    Returns
    -------
    dict
        ``{statistic: {"synthetic": median, "recorded": median, "ratio":
        synthetic / recorded}}`` for each name in :data:`STATISTICS`.
    """
    return _compare(synthetic, recorded, realism_stats, STATISTICS)


def _table(a: Mapping[str, Any], b: Mapping[str, Any], keys: Sequence[str]
           ) -> dict[str, dict[str, float]]:
    table = {}
    for key in keys:
        s, r = float(a["median"][key]), float(b["median"][key])
        table[key] = {"synthetic": s, "recorded": r, "ratio": s / r if r else float("nan")}
    return table


def _modality(demo: Demonstration, name: str) -> FloatArray:
    """The columns of modality ``name`` of ``demo``, shape (T, k)."""
    if name not in [m.name for m in demo.modalities]:
        raise ValueError(f"demos: expected the 'hand' and 'arm' modalities, got "
                         f"{[m.name for m in demo.modalities]} ({demo.source or demo.task})")
    return demo.select(name).human


def arm_track_stats(times: FloatArray, hand: FloatArray, arm: FloatArray) -> dict[str, float]:
    """Per-demonstration arm statistics (see the module docstring).

    Parameters
    ----------
    times : array_like, shape (T,)
        Non-decreasing sample times (s).
    hand : array_like, shape (T, 3)
        Hand positions (m).
    arm : array_like, shape (T, 6)
        Elbow x, y, z and shoulder x, y, z (m).

    Returns
    -------
    dict
        ``elbow_path``, ``elbow_hand``, ``shoulder_path``, ``shoulder_travel``,
        ``upper_arm`` (m) and ``shoulder_start`` (ndarray, shape (3,), m).
    """
    times = np.asarray(times, dtype=float)
    arm = check_array(arm, "arm", 2, shape=(times.size, 6), allow_nan=True)
    elbow, shoulder = arm[:, :3], arm[:, 3:]
    _, rows = valid_rows(times, np.column_stack([np.asarray(hand, dtype=float), arm]))
    if not rows.size:
        raise ValueError("arm: expected at least one valid row, got none")
    start, end = end_points(times, shoulder)
    return {
        "elbow_path": _path_length(times, elbow),
        "elbow_hand": float(np.median(np.linalg.norm(rows[:, :3] - rows[:, 3:6], axis=1))),
        "shoulder_path": _path_length(times, shoulder),
        "shoulder_travel": float(np.linalg.norm(end - start)),
        "upper_arm": float(np.median(np.linalg.norm(rows[:, 3:6] - rows[:, 6:], axis=1))),
        "shoulder_start": start,
    }


def _path_length(times: FloatArray, track: FloatArray) -> float:
    """Length (m) of the robustly filtered ``track`` (T, 3)."""
    _, smooth = smooth_track(times, track)
    return float(np.sum(np.linalg.norm(np.diff(smooth, axis=0), axis=1)))


def arm_realism_stats(demos: Sequence[Demonstration]) -> dict[str, Any]:
    """Robust statistics of the human arm of a set of demonstrations.

    Parameters
    ----------
    demos : sequence of Demonstration
        At least one, each with the ``hand`` and ``arm`` modalities
        (:data:`sandbox.data.spec.HAND`, :data:`sandbox.data.spec.ARM`; m).

    Returns
    -------
    dict
        One array of shape (n,) per name in :data:`ARM_STATISTICS` (m), plus
        ``"median"``: a dict of their medians and ``"n"``: the number of
        demonstrations.
    """
    demos = list(demos)
    if not demos or not all(isinstance(d, Demonstration) for d in demos):
        raise ValueError("demos: expected a non-empty sequence of Demonstration")
    rows = [arm_track_stats(d.times, _modality(d, "hand"), _modality(d, "arm")) for d in demos]
    out: dict[str, Any] = {k: np.array([r[k] for r in rows]) for k in ARM_STATISTICS
                           if k != "shoulder_spread"}
    starts = np.array([r["shoulder_start"] for r in rows])
    out["shoulder_spread"] = _spread(starts, [d.task for d in demos])
    return _with_medians(out, ARM_STATISTICS, len(demos))


def compare_arm_realism(
    synthetic: Sequence[Demonstration] | Mapping[str, Any],
    recorded: Sequence[Demonstration] | Mapping[str, Any],
) -> dict[str, dict[str, float]]:
    """Synthetic vs recorded medians of each arm statistic (as :func:`compare_realism`).

    Parameters
    ----------
    synthetic, recorded : sequence of Demonstration or dict
        Demonstrations with the hand and the arm, or the output of
        :func:`arm_realism_stats` for them.

    Returns
    -------
    dict
        ``{statistic: {"synthetic": median, "recorded": median, "ratio":
        synthetic / recorded}}`` for each name in :data:`ARM_STATISTICS`.
    """
    return _compare(synthetic, recorded, arm_realism_stats, ARM_STATISTICS)


def format_realism(table: Mapping[str, Mapping[str, float]]) -> str:
    """The table of :func:`compare_realism` as aligned text, one statistic per line."""
    w = max([14, *(len(key) + 1 for key in table)])
    lines = [f"{'statistic':<{w}}{'synthetic':>11}{'recorded':>11}{'ratio':>8}"]
    for key, row in table.items():
        lines.append(
            f"{key:<{w}}{row['synthetic']:>11.3f}{row['recorded']:>11.3f}{row['ratio']:>8.2f}"
        )
    return "\n".join(lines)
