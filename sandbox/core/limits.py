"""Documented limits checked at the public boundary.

Nothing in the method needs unbounded sizes: a handover lasts seconds, a
trajectory has tens of basis functions. These limits turn a careless input
(a trial stamped in milliseconds, a stray 1e6 s timestamp) into a clear
``ValueError`` instead of a multi-gigabyte allocation. Each message names the
limit and, where it can be raised, how.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

#: Longest demonstration, trial or plan horizon accepted (s). Handovers last
#: 1-10 s; a minute leaves ample room. Raise it with ``max_duration=``.
MAX_DURATION_S = 60.0

#: Shortest median sample interval accepted (s): 10 kHz. Finer spacing on a
#: motion of human duration means the times are not in seconds.
MIN_MEDIAN_DT_S = 1e-4


def check_duration(times: ArrayLike, name: str = "times", max_duration: float = MAX_DURATION_S) -> float:
    """Return the span of increasing ``times`` (s) after checking it is plausible.

    Parameters
    ----------
    times : array_like, shape (T,)
        Increasing finite sample times (s); already validated by ``check_times``.
    name : str
        Name used in error messages.
    max_duration : float
        Largest span accepted (s).

    Raises
    ------
    ValueError
        If the span exceeds ``max_duration`` or the median sample interval is
        below ``MIN_MEDIAN_DT_S``; the message says which unit the times look
        like (milliseconds, microseconds, nanoseconds).
    """
    t = np.asarray(times, dtype=np.float64)
    span = float(t[-1] - t[0]) if t.size else 0.0
    dt = float(np.median(np.diff(t))) if t.size > 1 else np.inf
    if span > max_duration:
        raise ValueError(
            f"{name}: expected at most {max_duration:g} s, got a span of {span:g} s"
            f"{_unit_hint(span, dt)}; raise max_duration= if this is really seconds"
        )
    if dt < MIN_MEDIAN_DT_S:
        raise ValueError(
            f"{name}: expected sample intervals of at least {MIN_MEDIAN_DT_S:g} s, got a median of "
            f"{dt:g} s{_unit_hint(span, dt)}"
        )
    return span


def _unit_hint(span: float, dt: float) -> str:
    """Say which unit ``times`` look like when read as seconds gives a human-scale motion."""
    for unit, factor in (("milliseconds", 1e3), ("microseconds", 1e6), ("nanoseconds", 1e9)):
        if 0.2 <= span / factor <= MAX_DURATION_S and (not np.isfinite(dt) or dt / factor >= 1e-4):
            return f" (looks like {unit}: divide by {factor:g})"
    if np.isfinite(dt) and dt > 1.0:
        return " (samples further apart than 1 s: absolute or unscaled timestamps?)"
    return ""
