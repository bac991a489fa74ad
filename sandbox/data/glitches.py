"""Tracker glitches of a recorded human track: repeats, (0, 0, 0) rows, freezes, jumps.

Numpy only; used by the loader (:mod:`sandbox.data.recorded`) to report what a
recording contains and to decide which rows carry a new tracker frame.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from sandbox.validation import FloatArray, check_array, check_positive


@dataclass(frozen=True)
class Glitches:
    """Tracker glitches of a recorded human track, one flag per row, shape (T,).

    Attributes
    ----------
    fresh : ndarray of bool
        Rows carrying a new tracker frame: not missing, not (0, ..., 0), not a repeat.
    missing : ndarray of bool
        Rows with a NaN human value.
    zero : ndarray of bool
        Rows whose human values are all exactly 0 (tracker lost the person).
    stale : ndarray of bool
        Rows repeating a frame received before (one of the last ``repeat_window``).
    jump : ndarray of bool
        Fresh rows at least ``jump_m`` (m) away from the previous fresh row.
    frozen : ndarray of bool
        Stale rows of a run that repeats one frame for longer than ``freeze_s`` (s).
    frozen_segments : int
        Number of such runs.
    frozen_s : float
        Their total duration (s).
    """

    fresh: np.ndarray
    missing: np.ndarray
    zero: np.ndarray
    stale: np.ndarray
    jump: np.ndarray
    frozen: np.ndarray
    frozen_segments: int
    frozen_s: float

    def counts(self) -> dict[str, int | float]:
        """Row counts of each glitch (JSON-ready)."""
        return {
            "new_frames": int(self.fresh.sum()), "stale_rows": int(self.stale.sum()),
            "zero_rows": int(self.zero.sum()), "missing_rows": int(self.missing.sum()),
            "jumps": int(self.jump.sum()), "frozen_rows": int(self.frozen.sum()),
            "frozen_segments": self.frozen_segments, "frozen_s": round(self.frozen_s, 4),
        }


def find_glitches(
    times: ArrayLike,
    values: ArrayLike,
    *,
    freeze_s: float = 0.25,
    jump_m: float = 0.05,
    repeat_window: int = 64,
) -> Glitches:
    """Classify the rows of a recorded human track (no filtering, numpy only).

    Parameters
    ----------
    times : array_like, shape (T,)
        Row times (s), non-decreasing.
    values : array_like, shape (T, P)
        Human positions (m), NaN where missing.
    freeze_s : float
        A frame repeated for longer than this (s) is a frozen skeleton.
    jump_m : float
        Step between consecutive new frames that counts as a jump (m).
    repeat_window : int
        How many recent distinct frames a repeat is looked for among.
    """
    t = check_array(times, "times", 1)
    y = check_array(values, "values", 2, shape=(t.size, None), allow_nan=True)
    missing = np.isnan(y).any(axis=1)
    zero = ~missing & np.all(y == 0.0, axis=1)
    stale = np.zeros(t.size, dtype=bool)
    recent: deque[bytes] = deque(maxlen=int(repeat_window))
    for k in np.flatnonzero(~missing & ~zero):
        key = y[k].tobytes()
        stale[k] = key in recent
        if not stale[k]:
            recent.append(key)
    fresh = ~missing & ~zero & ~stale
    jump = np.zeros(t.size, dtype=bool)
    idx = np.flatnonzero(fresh)
    jump[idx[1:]] = np.linalg.norm(np.diff(y[idx], axis=0), axis=1) >= jump_m
    frozen, n_seg, total = _frozen_runs(t, fresh, stale, freeze_s)
    return Glitches(fresh, missing, zero, stale, jump, frozen, n_seg, total)


def _frozen_runs(
    t: FloatArray, fresh: np.ndarray, stale: np.ndarray, freeze_s: float
) -> tuple[np.ndarray, int, float]:
    """Stale rows in runs lasting longer than ``freeze_s`` after the last new frame."""
    frozen = np.zeros(t.size, dtype=bool)
    n_seg, total = 0, 0.0
    k = 0
    while k < t.size:
        if not stale[k]:
            k += 1
            continue
        end = k
        while end + 1 < t.size and stale[end + 1]:
            end += 1
        before = np.flatnonzero(fresh[:k])
        start_t = t[before[-1]] if before.size else t[k]
        if t[end] - start_t > freeze_s:
            frozen[k : end + 1] = True
            n_seg, total = n_seg + 1, total + float(t[end] - start_t)
        k = end + 1
    return frozen, n_seg, total


def excursions(
    times: ArrayLike,
    values: ArrayLike,
    *,
    window_s: float = 0.5,
    threshold_m: float = 0.04,
) -> np.ndarray:
    """Flag samples that leave the track's running median (non-causal).

    For each valid sample, the per-axis median of the valid samples around it
    is taken: as many on each side, as many as fit within ``window_s / 2`` on
    both sides (so the window shrinks near the ends of the track and of
    dropouts instead of becoming lopsided); a sample farther than
    ``threshold_m`` (m) from it is part of an excursion. A running median leaves
    monotonic motion unchanged and ignores any excursion shorter than about
    half the window, which is what the tracker's occlusion jumps are (mostly
    2-3 frames). It uses later samples: offline (training demos) only.

    Parameters
    ----------
    times : array_like, shape (T,)
        Sample times (s), non-decreasing.
    values : array_like, shape (T, P)
        Positions (m), NaN where there is no sample to judge.
    window_s : float
        Width of the median window (s).
    threshold_m : float
        Distance from the running median beyond which a sample is flagged (m).

    Returns
    -------
    ndarray of bool, shape (T,)
    """
    t = check_array(times, "times", 1)
    y = check_array(values, "values", 2, shape=(t.size, None), allow_nan=True)
    check_positive(window_s, "window_s")
    check_positive(threshold_m, "threshold_m")
    idx = np.flatnonzero(np.isfinite(y).all(axis=1))
    tv, yv = t[idx], y[idx]
    if idx.size == 0:
        return np.zeros(t.size, dtype=bool)
    # As many samples on each side (the fewer of the two within window_s / 2), so a
    # moving hand is not biased near the ends of the track or of a dropout.
    i = np.arange(idx.size)
    lo = np.searchsorted(tv, tv - window_s / 2, side="left")
    hi = np.searchsorted(tv, tv + window_s / 2, side="right")
    m = np.minimum(i - lo, hi - 1 - i)
    med = np.array([np.median(yv[k - r : k + r + 1], axis=0) for k, r in zip(i, m, strict=True)])
    out = np.zeros(t.size, dtype=bool)
    out[idx] = np.linalg.norm(yv - med, axis=1) > threshold_m
    return out
