"""Recording sessions: one calibration of the lab, drawn from a seed.

Real sessions of the same lab differ by the skeleton tracker's calibration
(its frame is offset by a few cm and rotated by a few degrees from Baxter's
base frame), by where the robot's fingertip meets the object relative to the
hand, by the tempo of the motions and by what the hand does once it has
handed the object over (the motion's *tail*). A :class:`Session` holds one such
calibration; :func:`draw_session` draws one from a seed, so that a session is
named by an integer (``make_dataset(..., session=3)``,
``python -m sandbox fit --data synthetic:objects --session 3``).

The tracker's frame
-------------------
A point :math:`p` of Baxter's base frame is reported by the tracker at

.. math::

    p' = R\\,(p - c) + c + o,

with :math:`R` the rotation of the rotation vector ``tracker_rotation`` (rad),
:math:`c` the pivot :data:`PIVOT` (m, a point in front of the robot, in the
middle of the hand's workspace) and :math:`o` the ``tracker_offset`` (m)
(:meth:`Session.to_tracker`). A rotation about the pivot rather than the base
frame's origin keeps a few degrees a few cm where the hand is.

Tails (what happens from the hand's arrival to the recording's end)
-------------------------------------------------------------------
``"none"``: today's synthetic data (the hand holds still, drifting ~1 cm).
``"stop_wait"``: the hand stops 3-8 cm short of its end point (back along
the approach) and waits there, still; the robot meets it there.
``"linger"``: the hand stays near its end with a slow wander of 1-3 cm.
``"drift_back"``: 0.1-0.3 s after the robot's arrival (the release) the hand
moves 10-25 cm back toward its start, smoothly.
``"overshoot"``: the hand passes its end point by 3-8 cm and comes back
before the robot arrives.
``"freeze"``: from a time in the last 30 % of the recording to its end the
tracker repeats its last frame (the measured track only).
Details and the draws: :mod:`sandbox.data.synthetic.tails`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from sandbox.robot import GRASP_OFFSET
from sandbox.validation import FloatArray, check_choice, check_integer, check_number

#: The tails a drawn session may have (:func:`draw_session` picks one uniformly).
TAILS = ("stop_wait", "linger", "drift_back", "overshoot", "freeze")
#: The tail of today's synthetic data: the hand holds still at its end.
NO_TAIL = "none"
#: Pivot (m, Baxter's base frame) of the tracker frame's rotation: in front of
#: the robot, between the hand's start and the handover points.
PIVOT = np.array([0.95, 0.05, 0.25])
PIVOT.setflags(write=False)
#: Ranges :func:`draw_session` draws from: tracker offset (m), rotation (deg),
#: per-axis shift (m) of the object offset from GRASP_OFFSET, tempo.
OFFSET_RANGE, ROTATION_DEG, OBJECT_SHIFT, TEMPO_RANGE = (0.02, 0.06), (1.0, 5.0), 0.04, (0.8, 1.25)
#: Accepted tempo (a session's motions take ``tempo`` times as long as today's).
TEMPO_LIMITS = (0.25, 4.0)
#: Largest accepted tracker offset and object offset (m), rotation (rad).
MAX_OFFSET_M, MAX_ROTATION = 0.5, np.pi


def _vector(value: object, name: str, limit: float, unit: str) -> FloatArray:
    """``value`` as a read-only (3,) float array, finite, norm <= ``limit``; else ValueError."""
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        arr = np.full(1, np.nan)
    if arr.shape != (3,) or not np.isfinite(arr).all() or np.linalg.norm(arr) > limit:
        raise ValueError(f"{name}: expected 3 finite numbers ({unit}) of norm <= {limit:g}, "
                         f"got {value!r}")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class Session:
    """One recording session's calibration.

    Parameters
    ----------
    seed : int or None
        The seed it was drawn from (:func:`draw_session`), None if built by hand.
    tracker_offset : array_like, shape (3,)
        Offset (m) of the tracker's frame: added after the rotation.
    tracker_rotation : array_like, shape (3,)
        Rotation vector (rad, axis times angle, norm <= pi) of the tracker's
        frame about :data:`PIVOT`.
    object_offset : array_like, shape (3,)
        Where the robot's fingertip meets the object (m), relative to the true
        hand at the handover, Baxter's base frame (today's data:
        :data:`~sandbox.robot.GRASP_OFFSET`); each demonstration adds its own
        small ``grasp_shift``.
    tempo : float
        Multiplies the motions' durations and onsets, in [0.25, 4] (1: today's).
    tail : str
        What the hand does after the handover: one of :data:`TAILS`, or
        ``"none"`` (today's: it holds still).
    """

    seed: int | None
    tracker_offset: FloatArray
    tracker_rotation: FloatArray
    object_offset: FloatArray
    tempo: float = 1.0
    tail: str = NO_TAIL

    def __post_init__(self) -> None:
        if self.seed is not None:
            object.__setattr__(self, "seed", check_integer(self.seed, "seed", 0))
        for key, limit, unit in (("tracker_offset", MAX_OFFSET_M, "m"),
                                 ("tracker_rotation", MAX_ROTATION, "rad"),
                                 ("object_offset", MAX_OFFSET_M, "m")):
            object.__setattr__(self, key, _vector(getattr(self, key), key, limit, unit))
        object.__setattr__(self, "tempo", check_number(self.tempo, "tempo", low=TEMPO_LIMITS[0],
                                                       high=TEMPO_LIMITS[1]))
        check_choice(self.tail, "tail", (*TAILS, NO_TAIL))

    @property
    def rotation_matrix(self) -> FloatArray:
        """The tracker frame's rotation :math:`R`, shape (3, 3)."""
        return Rotation.from_rotvec(np.array(self.tracker_rotation)).as_matrix()

    def to_tracker(self, points: FloatArray) -> FloatArray:
        """Where the tracker reports ``points`` (m): :math:`R (p - c) + c + o` per point.

        Parameters
        ----------
        points : ndarray, shape (T, 3k)
            Positions (m, Baxter's base frame), ``k`` points per row (the hand:
            3 columns; the elbow and shoulder: 6).

        Returns
        -------
        ndarray, shape (T, 3k)
            The same points in the tracker's frame (m); a new array.
        """
        points = np.asarray(points, dtype=float)
        rows = points.reshape(-1, 3) - PIVOT
        moved = rows @ self.rotation_matrix.T + PIVOT + self.tracker_offset
        return moved.reshape(points.shape)

    def to_dict(self) -> dict[str, Any]:
        """The session as JSON-able values (lists of floats)."""
        return {"seed": self.seed, "tracker_offset": self.tracker_offset.tolist(),
                "tracker_rotation": self.tracker_rotation.tolist(),
                "object_offset": self.object_offset.tolist(), "tempo": self.tempo,
                "tail": self.tail}

    @classmethod
    def from_dict(cls, values: dict[str, Any]) -> Session:
        """The session :meth:`to_dict` wrote; ``ValueError`` on a missing or extra key."""
        keys = ("seed", "tracker_offset", "tracker_rotation", "object_offset", "tempo", "tail")
        if not isinstance(values, dict) or set(values) != set(keys):
            got = sorted(values) if isinstance(values, dict) else type(values).__name__
            raise ValueError(f"session: expected a dict with keys {list(keys)}, got {got}")
        return cls(**values)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Session) and self.to_dict() == other.to_dict()

    def __hash__(self) -> int:
        return hash(repr(self.to_dict()))


def _direction(rng: np.random.Generator) -> FloatArray:
    """A uniformly random unit vector, shape (3,)."""
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def draw_session(seed: int, *, tail: str | None = None) -> Session:
    """The session of ``seed``: every field drawn from ``np.random.default_rng(seed)``.

    Draws, in this order: the tracker offset (2-6 cm, uniform, in a uniformly
    random direction), the rotation (1-5 degrees, uniform, about a random
    axis), the object offset (:data:`~sandbox.robot.GRASP_OFFSET` plus a shift
    uniform in +/- 4 cm per axis; with the tracker offset, two sessions' offsets
    from the tracked hand to the fingertip typically differ by more than the
    environment's 5 cm grasp radius), the tempo (log-uniform in [0.8, 1.25])
    and the tail (uniform among :data:`TAILS`). The tail is drawn even when
    given, so ``draw_session(s, tail=k)`` has the calibration of ``draw_session(s)``.

    Parameters
    ----------
    seed : int
        The session's seed (>= 0).
    tail : str, optional
        One of :data:`TAILS` or ``"none"``: replaces the drawn tail.

    Returns
    -------
    Session
    """
    seed = check_integer(seed, "session", 0)
    if tail is not None:
        check_choice(tail, "tail", (*TAILS, NO_TAIL))
    rng = np.random.default_rng(seed)
    offset = rng.uniform(*OFFSET_RANGE) * _direction(rng)
    rotation = np.deg2rad(rng.uniform(*ROTATION_DEG)) * _direction(rng)
    obj = GRASP_OFFSET + rng.uniform(-OBJECT_SHIFT, OBJECT_SHIFT, 3)
    tempo = float(np.exp(rng.uniform(*np.log(TEMPO_RANGE))))
    drawn = TAILS[int(rng.integers(len(TAILS)))]
    return Session(seed=seed, tracker_offset=offset, tracker_rotation=rotation,
                   object_offset=obj, tempo=tempo, tail=drawn if tail is None else tail)


def as_session(session: Session | int | None) -> Session | None:
    """``session`` as a :class:`Session`: None stays None, an integer >= 0 is drawn.

    ``ValueError`` on anything else (a negative integer, a string, a bool).
    """
    if session is None or isinstance(session, Session):
        return session
    if isinstance(session, (bool, np.bool_)) or not isinstance(session, (int, np.integer)):
        raise ValueError(f"session: expected None, an integer >= 0 or a Session, "
                         f"got {session!r}")
    return draw_session(int(session))
