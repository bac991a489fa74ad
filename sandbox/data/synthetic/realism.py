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
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from scipy.ndimage import median_filter, uniform_filter1d

from sandbox.core.validation import FloatArray, check_array, check_positive
from sandbox.data.demonstration import Demonstration

#: Statistics computed by :func:`realism_stats`, in report order.
STATISTICS = ("duration", "path_length", "peak_speed", "reach_time", "end_spread", "start_spread")


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
        At least one; ``human`` must hold the hand x, y, z (m) (P = 3).

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
    if any(d.human.shape[1] != 3 for d in demos):
        raise ValueError("demos: expected human hand positions with P = 3 dims")
    rows = [track_stats(d.times, d.human) for d in demos]
    out: dict[str, Any] = {k: np.array([r[k] for r in rows]) for k in rows[0]}
    ends = np.array([end_points(d.times, d.human) for d in demos])  # (n, 2, 3)
    tasks = [d.task for d in demos]
    out["end_spread"] = _spread(ends[:, 1], tasks)
    out["start_spread"] = _spread(ends[:, 0], tasks)
    out["median"] = {k: float(np.median(out[k])) for k in STATISTICS}
    out["n"] = len(demos)
    return out


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
    a = synthetic if isinstance(synthetic, Mapping) else realism_stats(synthetic)
    b = recorded if isinstance(recorded, Mapping) else realism_stats(recorded)
    table = {}
    for key in STATISTICS:
        s, r = float(a["median"][key]), float(b["median"][key])
        table[key] = {"synthetic": s, "recorded": r, "ratio": s / r if r else float("nan")}
    return table


def format_realism(table: Mapping[str, Mapping[str, float]]) -> str:
    """The table of :func:`compare_realism` as aligned text, one statistic per line."""
    lines = [f"{'statistic':<14}{'synthetic':>11}{'recorded':>11}{'ratio':>8}"]
    for key, row in table.items():
        lines.append(
            f"{key:<14}{row['synthetic']:>11.3f}{row['recorded']:>11.3f}{row['ratio']:>8.2f}"
        )
    return "\n".join(lines)
