"""The human: a hand motion (true path and tracker measurements) and a kinematic hand body.

A :class:`HumanMotion` holds one episode's hand trajectory in Baxter's base
frame: the *true* path that drives the hand body (and the object it holds)
and what the skeleton tracker *measured* (steps, jumps, dropouts as NaN), which
is what the robot observes. After its last sample the hand holds still. It
may also carry what the tracker measured of the rest of the body
(:data:`BODY_DIMS`: the same-side elbow and shoulder ``arm``, the ``emg``
envelope), NaN where it measured nothing.

:class:`HumanHand` is the kinematic hand/forearm body (``urdf/human_hand.urdf``,
no mass): the environment teleports it along the true path at every control
step, its forearm pointing from the hand toward the human's shoulder.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sandbox import urdf
from sandbox.envs.pybullet import Simulation
from sandbox.validation import check_array, check_positive, check_times

FloatArray = NDArray[np.float64]

#: Where the forearm points to (m, Baxter's base frame): the human's left
#: shoulder in the recordings, lowered to elbow height (the forearm's far end
#: is drawn 0.31 m from the hand along this direction).
SHOULDER = np.array([1.36, 0.0, 0.15])
_SHOULDER: list[float] = SHOULDER.tolist()
#: Body modalities a motion may carry besides the hand, and their dims: the
#: tracked elbow then shoulder (x, y, z each, m) and the 8-channel EMG envelope.
BODY_DIMS = {"arm": 6, "emg": 8}


@dataclass(frozen=True, eq=False)
class HumanMotion:
    """One episode's hand motion.

    Parameters
    ----------
    times : array_like, shape (T,)
        Sample times (s), strictly increasing, starting at 0.
    true : array_like, shape (T, 3)
        True hand positions (m), finite: they drive the hand body.
    measured : array_like, shape (T, 3)
        Tracker measurements (m); NaN marks a dropout.
    task : str
        The task the human performs.
    source : str
        Where the motion came from (generator and seed, or file).
    meta : mapping
        Anything else (e.g. the recorded trial's preprocessing report).
    body : mapping of str to array_like, optional
        Other measured modalities (keys among :data:`BODY_DIMS`), each shape
        (T, dims), NaN where nothing was measured; a modality left out is
        unobserved (all NaN).
    """

    times: FloatArray
    true: FloatArray
    measured: FloatArray
    task: str
    source: str = ""
    meta: Mapping[str, Any] = field(default_factory=dict)
    body: Mapping[str, FloatArray] = field(default_factory=dict)

    def __post_init__(self) -> None:
        times = check_times(self.times, "times")
        if abs(times[0]) > 1e-9:
            raise ValueError(f"times: expected the motion to start at 0 s, got {times[0]:g}")
        true = check_array(self.true, "true", 2, shape=(times.size, 3))
        measured = check_array(self.measured, "measured", 2, shape=(times.size, 3),
                               allow_nan=True)
        valid = np.isfinite(measured).all(axis=1)
        if not valid.any():
            raise ValueError("measured: expected at least one sample without NaN, got none")
        last = _last_valid(valid)
        last[last < 0] = int(np.argmax(valid))  # before the first valid sample: that one
        for name, value in (("times", times), ("true", true), ("measured", measured),
                            ("_last_valid", last), ("_frame_row", _frame_rows(measured, last))):
            value.setflags(write=False)
            object.__setattr__(self, name, value)
        object.__setattr__(self, "_lists", (times.tolist(), true.tolist()))   # for position()
        object.__setattr__(self, "meta", dict(self.meta))
        object.__setattr__(self, "body", _check_body(self.body, times.size))
        object.__setattr__(self, "_body_last", {
            name: _last_valid(np.isfinite(v).all(axis=1)) for name, v in self.body.items()})

    @property
    def duration(self) -> float:
        """Time of the last sample (s)."""
        return float(self.times[-1])

    def position(self, t: float) -> FloatArray:
        """True hand position (3,) m at time ``t`` (s), linearly interpolated; held at the ends.

        In Python floats (the same arithmetic as on arrays): it runs at every physics step.
        """
        return np.array(self.positions([t])[0])

    def positions(self, times: list[float]) -> list[list[float]]:
        """:meth:`position` at each of ``times`` (s), as lists of three floats (m): a control
        step's substeps in one call."""
        out, (ts, true), last, right = [], self._lists, len(self._lists[0]) - 1, bisect.bisect_right
        for t in times:                # min(max(x, low), high) written as comparisons
            i = right(ts, t)
            i = 1 if i < 1 else i
            i = last if i > last else i
            t0, t1 = ts[i - 1], ts[i]
            w = (t - t0) / (t1 - t0)
            w = 0.0 if w < 0.0 else 1.0 if w > 1.0 else w
            a, b, v = true[i - 1], true[i], 1.0 - w
            out.append([v * a[0] + w * b[0], v * a[1] + w * b[1], v * a[2] + w * b[2]])
        return out

    def measurement(self, t: float) -> FloatArray:
        """Latest valid tracker sample (3,) m at or before ``t`` (s)."""
        return self.measured[self._last_valid[self._row(t)]].copy()

    def frame_time(self, t: float) -> float:
        """Time (s) of the tracker frame :meth:`measurement` gives at ``t`` (s): the first
        row that carried it (the tracker repeats a frame on the rows until the next one)."""
        return float(self.times[self._frame_row[self._row(t)]])

    def _row(self, t: float) -> int:
        """The last row at or before ``t`` (s) (the first row before the recording)."""
        return max(bisect.bisect_right(self._lists[0], t) - 1, 0)

    def tracked(self, t: float) -> tuple[FloatArray, float, dict[str, FloatArray | None]]:
        """What the tracker gives at ``t`` (s), found once: :meth:`measurement` (3,) m, its
        :meth:`frame_time` (s), and for each body modality the motion carries, the
        :meth:`body_measurement` (dims,) or None before its first valid sample (a modality
        not carried is left out). The arrays are read-only views of the motion's own."""
        row = self._row(t)
        body = {name: (None if (i := int(last[row])) < 0 else self.body[name][i])
                for name, last in self._body_last.items()}
        return (self.measured[self._last_valid[row]], float(self.times[self._frame_row[row]]),
                body)

    def body_measurement(self, name: str, t: float) -> FloatArray:
        """Latest valid sample (dims,) of body modality ``name`` at or before ``t`` (s).

        All NaN before the modality's first valid sample, or if the motion
        does not carry it. ``name`` is one of :data:`BODY_DIMS`.
        """
        if name not in BODY_DIMS:
            raise ValueError(f"name: expected one of {list(BODY_DIMS)}, got {name!r}")
        if name not in self.body:
            return np.full(BODY_DIMS[name], np.nan)
        i = int(self._body_last[name][self._row(t)])
        return self.body[name][i].copy() if i >= 0 else np.full(BODY_DIMS[name], np.nan)

    def scaled(self, speed: float) -> HumanMotion:
        """The same motion played ``speed`` times faster (times divided by ``speed``)."""
        speed = check_positive(speed, "speed")
        return HumanMotion(self.times / speed, self.true, self.measured, self.task,
                           self.source, {**self.meta, "speed": speed}, self.body)


def _last_valid(valid: NDArray[np.bool_]) -> NDArray[np.int64]:
    """Index of the latest ``valid`` sample at or before each sample (-1 before the first)."""
    return np.maximum.accumulate(np.where(valid, np.arange(valid.size), -1))


def _frame_rows(measured: FloatArray, last: NDArray[np.int64]) -> NDArray[np.int64]:
    """Row where the frame held at each row first appeared (a valid row differing from the
    previous valid one starts a frame; ``last``: the latest valid row at each row)."""
    rows = np.flatnonzero(np.isfinite(measured).all(axis=1))
    values = measured[rows]
    new = np.r_[True, np.any(values[1:] != values[:-1], axis=1)]
    start = np.full(measured.shape[0], -1)
    start[rows] = rows[np.maximum.accumulate(np.where(new, np.arange(rows.size), 0))]
    return start[last]


def _check_body(body: Mapping[str, Any], n: int) -> dict[str, FloatArray]:
    """Validated, read-only copies of a motion's body modalities (see :class:`HumanMotion`)."""
    if not isinstance(body, Mapping):
        raise ValueError(f"body: expected a mapping of modality name to array, "
                         f"got {type(body).__name__}")
    out = {}
    for name, values in body.items():
        if name not in BODY_DIMS:
            raise ValueError(f"body: expected keys among {list(BODY_DIMS)}, got {name!r}")
        out[name] = check_array(values, f"body[{name!r}]", 2, shape=(n, BODY_DIMS[name]),
                                allow_nan=True)
        out[name].setflags(write=False)
    return out


def forearm_orientation(hand: FloatArray) -> tuple[float, float, float, float]:
    """Quaternion (x, y, z, w) turning the body's +x toward :data:`SHOULDER`, z kept up-ish.

    The body's y axis is horizontal (z_world x x), its z axis completes the frame.
    Written out in floats: it runs at every control step.
    """
    h0, h1, h2 = hand if type(hand) is list else np.asarray(hand, dtype=float).tolist()
    dx, dy, dz = _SHOULDER[0] - h0, _SHOULDER[1] - h1, _SHOULDER[2] - h2
    n = max(math.sqrt(dx * dx + dy * dy + dz * dz), 1e-9)
    x = (dx / n, dy / n, dz / n)
    h = max(math.hypot(x[0], x[1]), 1e-9)
    y = (-x[1] / h, x[0] / h, 0.0)
    z = (-x[2] * y[1], x[2] * y[0], x[0] * y[1] - x[1] * y[0])
    return _quaternion_rows([[x[0], y[0], z[0]], [x[1], y[1], z[1]], [x[2], y[2], z[2]]])


def _quaternion(R) -> tuple[float, float, float, float]:
    """Quaternion (x, y, z, w) of a rotation matrix (3, 3) (an array or rows of floats),
    stable for any rotation. In Python floats: it runs at every control step."""
    return _quaternion_rows([[float(v) for v in row] for row in R])


def _quaternion_rows(R: list[list[float]]) -> tuple[float, float, float, float]:
    """:func:`_quaternion` of a rotation matrix given as three rows of three floats."""
    trace = R[0][0] + R[1][1] + R[2][2]
    if trace > 0:
        s = 2.0 * math.sqrt(1.0 + trace)
        q = [(R[2][1] - R[1][2]) / s, (R[0][2] - R[2][0]) / s, (R[1][0] - R[0][1]) / s, s / 4]
    else:
        i = max(range(3), key=lambda m: R[m][m])          # the first largest, as np.argmax
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * math.sqrt(1.0 + R[i][i] - R[j][j] - R[k][k])
        q = [0.0, 0.0, 0.0, (R[k][j] - R[j][k]) / s]
        q[i], q[j], q[k] = s / 4, (R[j][i] + R[i][j]) / s, (R[k][i] + R[i][k]) / s
    return (q[0], q[1], q[2], q[3])


class HumanHand:
    """The kinematic hand/forearm body (``"human_hand"``), moved by teleporting.

    Parameters
    ----------
    sim : Simulation
        Where to load it.
    """

    name = "human_hand"

    def __init__(self, sim: Simulation) -> None:
        self.sim = sim
        sim.load_urdf(self.name, urdf.path("human_hand"), SHOULDER - [0.3, 0.0, 0.0])

    def move_to(self, position: FloatArray) -> None:
        """Put the tracked hand point at ``position`` (3,) m, the forearm toward the shoulder."""
        self.sim.set_pose(self.name, position, forearm_orientation(position))
