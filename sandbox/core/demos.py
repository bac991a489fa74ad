"""Checks of what :meth:`~sandbox.core.model.IProMP.fit` is given, before anything is fitted.

A demonstration (``sandbox.data.Demonstration`` or anything with the same
attributes, see :class:`~sandbox.core.model.DemonstrationLike`) must have

* ``times`` (T,): strictly increasing seconds, T >= 2, spanning at most
  ``max_duration`` (:func:`~sandbox.core.limits.check_duration`, which says when
  the times look like milliseconds or nanoseconds);
* ``human`` (T, P), NaN where missing, and ``robot`` (T, Q), finite, with
  1 <= P, Q <= :data:`~sandbox.core.limits.MAX_DIMS` and every value within
  :data:`~sandbox.core.limits.MAX_ABS_VALUE`;
* ``task``: a non-empty string.

:func:`check_spread` refuses a task whose demonstrations do not differ
(duplicated, constant or all-zero demos): its weight covariance would be zero
up to round-off, and no prediction can be made from it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from sandbox.core.limits import MAX_ABS_VALUE, MAX_DIMS, MIN_RELATIVE_SPREAD, check_duration
from sandbox.core.modality import Modality, check_modalities, default_modalities
from sandbox.validation import FloatArray, check_array, check_times

ATTRIBUTES = ("times", "human", "robot", "task")


def as_demo_list(demos) -> list:
    """``demos`` as a list, or a ``ValueError`` if it is not a sequence of demonstrations."""
    if demos is None or isinstance(demos, (str, bytes, Mapping)) or not hasattr(demos, "__len__"):
        raise ValueError(f"demos: expected a sequence of demonstrations, got "
                         f"{type(demos).__name__}")
    out = list(demos)
    if not out:
        raise ValueError("demos: expected at least two demonstrations per task, got none")
    return out


def check_demo(demo, name: str, max_duration: float) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Validated copies of one demonstration's times (T,), human (T, P) and robot (T, Q).

    Raises ``ValueError`` naming ``name`` and what is wrong (module docstring).
    """
    for attr in ATTRIBUTES:
        if not hasattr(demo, attr):
            raise ValueError(f"{name}: expected a Demonstration, missing {attr!r}")
    if not isinstance(demo.task, str) or not demo.task:
        raise ValueError(f"{name}.task: expected a non-empty task name, got {demo.task!r}")
    human = check_array(demo.human, f"{name}.human", 2, allow_nan=True)
    robot = check_array(demo.robot, f"{name}.robot", 2)
    times = check_times(demo.times, f"{name}.times")
    if human.shape[0] != times.size or robot.shape[0] != times.size:
        raise ValueError(f"{name}: expected increasing times matching {times.size} rows, got "
                         f"{human.shape[0]} human and {robot.shape[0]} robot rows")
    for part, arr in (("human", human), ("robot", robot)):
        if not 1 <= arr.shape[1] <= MAX_DIMS:
            raise ValueError(f"{name}.{part}: expected 1 to {MAX_DIMS} dims (limits.MAX_DIMS), "
                             f"got {arr.shape[1]}")
        big = np.abs(arr[np.isfinite(arr)])
        if big.size and big.max() > MAX_ABS_VALUE:
            raise ValueError(f"{name}.{part}: expected values within +/-{MAX_ABS_VALUE:g} "
                             f"(limits.MAX_ABS_VALUE), got {big.max():g}")
    check_duration(times, f"{name}.times", max_duration)
    return times, human, robot


def check_demos(demos: Sequence, max_duration: float) -> None:
    """Each demonstration valid (:func:`check_demo`), all with the first one's P, Q, modalities."""
    first = None
    for i, d in enumerate(demos):
        _, h, r = check_demo(d, f"demos[{i}]", max_duration)
        mods = modalities_of(d, h.shape[1])
        if first is None:
            first = (h.shape[1], r.shape[1], mods)
            continue
        P, Q, want = first
        if (h.shape[1], r.shape[1]) != (P, Q):
            raise ValueError(f"demos[{i}]: expected P={P}, Q={Q} like the first demo, "
                             f"got P={h.shape[1]}, Q={r.shape[1]}")
        if mods != want:
            raise ValueError(f"demos[{i}]: expected the modalities of the first demo "
                             f"{[m.name for m in want]}, got {[m.name for m in mods]}")


def modalities_of(demo, P: int) -> tuple[Modality, ...]:
    """A demonstration's modalities (default: one position modality over its human dims)."""
    try:
        mods = tuple(getattr(demo, "modalities", ()) or ())
        if mods:
            return check_modalities(mods, P)
        names = tuple(getattr(demo, "human_names", ()) or ())
    except TypeError:
        raise ValueError("demo: expected modalities and human_names to be sequences") from None
    names = names or tuple(f"human_{i}" for i in range(P))
    return check_modalities(default_modalities(names), P)


def check_spread(task: str, weights: FloatArray) -> None:
    """Refuse a task whose demonstrations' weights (n_demos, D*N) do not differ.

    The largest standard deviation of a weight across the demos must exceed
    :data:`~sandbox.core.limits.MIN_RELATIVE_SPREAD` times the largest weight
    magnitude (and be positive).
    """
    w = np.asarray(weights, dtype=np.float64)
    size = float(np.abs(w).max()) if w.size else 0.0
    spread = float(w.std(axis=0, ddof=1).max()) if w.shape[0] > 1 else 0.0
    if not spread > MIN_RELATIVE_SPREAD * size:
        raise ValueError(
            f"task {task!r}: its {w.shape[0]} demonstrations do not differ (the largest "
            f"standard deviation of their weights, {spread:.3g}, is not above "
            f"{MIN_RELATIVE_SPREAD:g} x their largest weight, {size:.3g}): duplicated, "
            f"constant or all-zero demonstrations have no spread to predict from; give "
            f"demonstrations of the task that differ"
        )
