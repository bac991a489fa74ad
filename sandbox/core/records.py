"""Calibration records pooled into arrays, and time bins that hold updates
(:mod:`sandbox.core.calibration`'s input side)."""

from __future__ import annotations

import numpy as np

from sandbox.core.conformal import ongoing
from sandbox.validation import FloatArray


def pool(records, n_tasks: int, end_prob: float | None = None):
    """Times, statistics (n, J), chosen tasks and owning record of every finite update of
    ``records`` (:meth:`~sandbox.core.calibration.Calibration.from_records`); with
    ``end_prob``, the updates past each motion's estimated end are left out."""
    if len(records) == 0:
        raise ValueError("records: expected at least one calibration motion, got none")
    time_parts: list[np.ndarray] = []
    value_parts: list[np.ndarray] = []
    tasks, owner = [], []
    for i, (t, v, k, *ended) in enumerate(records):
        t, v = np.asarray(t, dtype=np.float64), np.array(v, dtype=np.float64)
        v = v[:, None] if v.ndim == 1 else v
        k = np.asarray(k)
        if (t.ndim != 1 or v.ndim != 2 or t.shape != k.shape or v.shape[0] != t.size
                or (value_parts and v.shape[1] != value_parts[0].shape[1])):
            raise ValueError(f"records[{i}]: expected times, values and tasks of one length "
                             f"(values (s,) or (s, J), J alike in all records), got shapes "
                             f"{t.shape}, {v.shape} and {k.shape}")
        if k.size and (k.dtype.kind not in "iu" or k.min() < 0 or k.max() >= n_tasks):
            raise ValueError(f"records[{i}]: expected task indices in [0, {n_tasks}), got "
                             f"{k.tolist()[:10]}")
        if end_prob is not None:
            if not ended or np.shape(ended[0]) != t.shape:
                raise ValueError(f"records[{i}]: expected each update's ended probability "
                                 f"(a fourth entry, shape {t.shape}) to gate on, got "
                                 f"{np.shape(ended[0]) if ended else 'none'}")
            v[~ongoing(ended[0], end_prob)] = np.nan       # past the estimated end
        ok = np.isfinite(v[:, 0]) & np.isfinite(t)
        time_parts.append(t[ok])
        value_parts.append(np.where(np.isfinite(v[ok]), v[ok], 0.0))   # later NaN: no evidence
        tasks.append(k[ok].astype(np.int64))
        owner.append(np.full(int(ok.sum()), i))
    times, values = np.concatenate(time_parts), np.concatenate(value_parts)
    if times.size == 0:
        raise ValueError("records: expected finite statistics, got none")
    return times, values, np.concatenate(tasks), np.concatenate(owner)


def populated(edges: FloatArray, times: FloatArray) -> FloatArray:
    """Edges from 0 with at least one time in every bin (an empty bin joins the next
    populated one, or the one before at the end)."""
    edges = np.concatenate([[0.0], edges[edges > 0]])
    bins = np.searchsorted(edges, times, side="right") - 1
    kept = edges[np.bincount(bins, minlength=edges.size) > 0]
    kept[0] = 0.0
    return kept
