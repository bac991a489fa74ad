"""The ``segment:`` and ``resample_hz:`` keys of a spec: cut a long recording to the handover.

A recording often holds more than the reach: a pick-up before it, the transfer
and a retreat after. ``segment`` keeps the rows from the reach's onset to the
handover (the loader applies it before any preprocessing; times then restart
at 0)::

    segment:
      modality: hand                          # the observed hand (default hand)
      start: {rule: onset, speed: 0.15, distance_m: 0.1, before_s: 0.1}
      end: {rule: approach, within_m: 0.01, hold_s: 0.3}

``start``
    ``{rule: onset, speed: S, distance_m: D, before_s: B}``: the motion onset
    of the reach that ends at the handover: the last row before the end's
    reference row (the closest approach, or the last row) where the hand
    rests (slower than ``S`` m/s, default 0.15) at least ``D`` m (default 0.1)
    from where it is at the reference. The segment starts ``B`` s (default 0)
    before it. A pick-up that comes to rest before the reach is left out, and
    so is a pause of the corrective movements near the end (within ``D``).
    The speed is that of the hand smoothed over 0.1 s (gaps bridged linearly).
    ``{column: NAME}``: the first row where column NAME is non-zero.
``end``
    ``{rule: approach, within_m: W, hold_s: H}``: the closest approach of the
    observed hand and the robot part (the forward kinematics of Baxter's seven
    joints at :data:`~sandbox.robot.TIP_LINK`, both in the robot's base frame:
    give the ``frame`` first): the first row where their distance comes within
    ``W`` m (default 0.01) of its smallest value (a held handover is a plateau
    of distances, noisy), plus ``H`` s (default 0). Only the first approach
    counts: the distances after they first rise 5 cm above their running
    minimum (the parts leave each other) are not looked at. ``{column: NAME}``: the last row
    where column NAME is non-zero.

Either may be left out (the recording's first or last row). ``resample_hz: F``
thins a fast recording to at most one row per ``1 / F`` s (the last row of the
first time stamp at or after each step of a uniform grid; no interpolation).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from sandbox.validation import FloatArray, check_positive

#: Rules of ``segment.start`` (or a column).
START_RULES = ("onset",)
#: Rules of ``segment.end`` (or a column).
END_RULES = ("approach",)
#: Window (s) of the moving average smoothing the hand before its speed is taken.
SPEED_WINDOW_S = 0.1
#: The parts have left each other when their distance is this much (m) above its running
#: minimum (``approach`` looks no further).
LEAVE_M = 0.05
_KEYS = ("modality", "start", "end")
_RULE_KEYS = {"onset": ("rule", "speed", "distance_m", "before_s"),
              "approach": ("rule", "within_m", "hold_s")}


@dataclass(frozen=True)
class Bound:
    """One end of a segment: a rule with its numbers, or a column.

    Parameters
    ----------
    rule : {"onset", "approach", ""}
        The rule (empty with a column).
    column : str
        The column whose first (start) or last (end) non-zero row is the bound.
    value : float
        ``onset``: the speed threshold (m/s); ``approach``: ``within_m`` (m).
    margin_s : float
        ``onset``: ``before_s``; ``approach``: ``hold_s`` (s).
    distance_m : float
        ``onset``: how far from the end the hand rests (m).
    """

    rule: str = ""
    column: str = ""
    value: float = 0.0
    margin_s: float = 0.0
    distance_m: float = 0.1

    def to_dict(self) -> dict:
        """The spec's mapping of this bound."""
        if self.column:
            return {"column": self.column}
        if self.rule == "onset":
            return {"rule": "onset", "speed": self.value, "distance_m": self.distance_m,
                    "before_s": self.margin_s}
        return {"rule": "approach", "within_m": self.value, "hold_s": self.margin_s}


@dataclass(frozen=True)
class Segment:
    """Where each recording starts and ends (see the module docstring).

    Parameters
    ----------
    modality : str
        The position modality (3 columns) the rules look at.
    start, end : Bound or None
        The bounds (None: the recording's first or last row).
    """

    modality: str = "hand"
    start: Bound | None = None
    end: Bound | None = None

    @property
    def columns(self) -> tuple[str, ...]:
        """The trial columns the bounds read."""
        return tuple(b.column for b in (self.start, self.end) if b is not None and b.column)

    @property
    def needs_robot(self) -> bool:
        """Whether the end is the closest approach (the robot part's position is needed)."""
        return self.end is not None and self.end.rule == "approach"

    def to_dict(self) -> dict:
        """The spec's ``segment:`` mapping."""
        out: dict[str, Any] = {"modality": self.modality}
        for name in ("start", "end"):
            bound = getattr(self, name)
            if bound is not None:
                out[name] = bound.to_dict()
        return out


def _bound(value: Any, key: str, rules: tuple[str, ...]) -> Bound:
    want = f"{{rule: {rules[0]}, ...}} or {{column: NAME}}"
    if not isinstance(value, Mapping):
        raise ValueError(f"{key}: expected {want}, got {value!r}")
    if "column" in value:
        if set(value) != {"column"} or not isinstance(value["column"], str) \
                or not value["column"].strip():
            raise ValueError(f"{key}: expected {{column: NAME}} alone, got {dict(value)!r}")
        return Bound(column=value["column"].strip())
    rule = value.get("rule")
    if rule not in rules:
        raise ValueError(f"{key}.rule: expected one of {list(rules)} (or column: NAME), "
                         f"got {rule!r}")
    unknown = sorted(set(value) - set(_RULE_KEYS[rule]))
    if unknown:
        raise ValueError(f"{key}: unknown keys {unknown}; expected some of "
                         f"{list(_RULE_KEYS[rule])}")
    if rule == "onset":
        speed = check_positive(value.get("speed", 0.15), f"{key}.speed (m/s)")
        before = check_positive(value.get("before_s", 0.0), f"{key}.before_s", allow_zero=True)
        distance = check_positive(value.get("distance_m", 0.1), f"{key}.distance_m (m)")
        return Bound(rule=rule, value=speed, margin_s=before, distance_m=distance)
    within = check_positive(value.get("within_m", 0.01), f"{key}.within_m (m)", allow_zero=True)
    return Bound(rule=rule, value=within,
                 margin_s=check_positive(value.get("hold_s", 0.0), f"{key}.hold_s",
                                         allow_zero=True))


def parse_segment(value: Any, key: str = "segment") -> Segment:
    """A :class:`Segment` from a spec's ``segment:`` mapping; ``ValueError`` naming the key."""
    if not isinstance(value, Mapping):
        raise ValueError(f"{key}: expected a mapping with some of {list(_KEYS)}, got {value!r}")
    unknown = sorted(set(value) - set(_KEYS))
    if unknown:
        raise ValueError(f"{key}: unknown keys {unknown}; expected some of {list(_KEYS)}")
    modality = value.get("modality", "hand")
    if not isinstance(modality, str) or not modality.strip():
        raise ValueError(f"{key}.modality: expected a modality name, got {modality!r}")
    start = None if value.get("start") is None else _bound(value["start"], f"{key}.start",
                                                           START_RULES)
    end = None if value.get("end") is None else _bound(value["end"], f"{key}.end", END_RULES)
    return Segment(modality.strip(), start, end)


def _filled(times: FloatArray, points: FloatArray) -> FloatArray:
    """Points (n, 3) with NaN gaps bridged linearly (held at the ends); all-NaN stays NaN."""
    out = np.array(points, dtype=float)
    for j in range(out.shape[1]):
        ok = np.isfinite(out[:, j])
        if ok.any():
            out[:, j] = np.interp(times, times[ok], out[ok, j])
    return out


def hand_speed(times: FloatArray, points: FloatArray) -> FloatArray:
    """Speed (n,) m/s of points (n, 3) m at times (n,) s, smoothed over :data:`SPEED_WINDOW_S`."""
    p = _filled(times, points)
    dt = float(np.median(np.diff(times))) if times.size > 1 else 1.0
    width = max(1, int(round(SPEED_WINDOW_S / max(dt, 1e-9))))
    kernel = np.ones(width) / width
    pad = np.pad(p, ((width // 2, width - 1 - width // 2), (0, 0)), mode="edge")
    smooth = np.column_stack([np.convolve(pad[:, j], kernel, mode="valid")
                              for j in range(p.shape[1])])
    step = np.gradient(times) if times.size > 1 else np.ones(1)
    step[step <= 0] = max(dt, 1e-9)
    return np.linalg.norm(np.gradient(smooth, axis=0), axis=1) / step


def _marked(table: Mapping[str, FloatArray], column: str, first: bool, key: str) -> int:
    values = np.nan_to_num(np.asarray(table[column], dtype=float))
    rows = np.flatnonzero(values != 0)
    if not rows.size:
        raise ValueError(f"{key}: column {column!r} is never non-zero")
    return int(rows[0] if first else rows[-1])


def bounds(segment: Segment, times: FloatArray, hand: FloatArray, robot: FloatArray | None,
           columns: Mapping[str, FloatArray]) -> tuple[int, int, dict]:
    """First and last row (inclusive) of the segment, and what was found.

    Parameters
    ----------
    segment : Segment
    times : ndarray, shape (n,)
        Row times (s), non-decreasing.
    hand : ndarray, shape (n, 3)
        The segment's modality (m, robot base frame), NaN where missing.
    robot : ndarray, shape (n, 3) or None
        The robot part's position (m, base frame); needed by ``end: approach``.
    columns : mapping of str to ndarray, shape (n,)
        The columns the bounds name.

    Raises
    ------
    ValueError
        A bound that finds nothing (the message names the key).
    """
    last, found = times.size - 1, {}
    reference = last
    if segment.end is not None and segment.end.column:
        last = reference = _marked(columns, segment.end.column, False, "segment.end")
    elif segment.end is not None:
        assert robot is not None
        distance = np.linalg.norm(hand - robot, axis=1)
        if not np.isfinite(distance).any():
            raise ValueError("segment.end: no row with both the hand and the robot part")
        distance = _first_approach(distance)
        closest = float(np.nanmin(distance))
        reference = int(np.flatnonzero(distance <= closest + segment.end.value)[0])
        last = int(np.searchsorted(times, times[reference] + segment.end.margin_s, "right")) - 1
        found["closest_approach_m"] = round(closest, 4)
    first = 0
    if segment.start is not None and segment.start.column:
        first = _marked(columns, segment.start.column, True, "segment.start")
    elif segment.start is not None:
        first = _onset(times, hand, reference, segment.start)
    if first >= last:
        raise ValueError(f"segment: the start ({times[first]:.2f} s) is not before the end "
                         f"({times[last]:.2f} s)")
    found.update(start_s=round(float(times[first]), 4), end_s=round(float(times[last]), 4))
    return first, last, found


def _first_approach(distance: FloatArray) -> FloatArray:
    """The distances up to where they first rise :data:`LEAVE_M` above their running minimum
    (the two part), NaN after; a later crossing of the retreating parts is left out."""
    running = np.fmin.accumulate(np.where(np.isfinite(distance), distance, np.inf))
    parted = np.flatnonzero(distance > running + LEAVE_M)
    out = np.array(distance, dtype=float)
    if parted.size:
        out[parted[0]:] = np.nan
    return out


def _onset(times: FloatArray, hand: FloatArray, reference: int, start: Bound) -> int:
    p = _filled(times, hand)
    speed = hand_speed(times, hand)
    away = np.linalg.norm(p - p[reference], axis=1) >= start.distance_m
    rest = np.flatnonzero((speed < start.value) & away)
    rest = rest[rest < reference]
    if not rest.size:
        raise ValueError(f"segment.start: the hand never rests (slower than {start.value:g} m/s) "
                         f"{start.distance_m:g} m or more from where it ends")
    return int(np.searchsorted(times, times[rest[-1]] - start.margin_s, "left"))


def thin(times: FloatArray, rate_hz: float) -> np.ndarray:
    """Rows (indices, increasing) kept by ``resample_hz`` (see the module docstring).

    ``times`` (n,) s is non-decreasing; of each chosen time stamp its last row is kept.
    """
    t = np.asarray(times, dtype=float)
    stamps = np.unique(t)
    grid = np.arange(stamps[0], stamps[-1] + 1e-9, 1.0 / rate_hz)
    chosen = np.unique(stamps[np.minimum(np.searchsorted(stamps, grid - 1e-9), stamps.size - 1)])
    return np.searchsorted(t, chosen, side="right") - 1
