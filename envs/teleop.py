"""A teleoperated human hand: it moves at a commanded velocity, the tracker sees it.

:class:`TeleopMotion` stands in for a :class:`~sandbox.envs.human.HumanMotion`
in the environment (same ``position(t)`` / ``measurement(t)`` interface), but
nothing is known in advance: a controller (the keyboard teleop of ``python -m
sandbox play``, or a test) sets the hand's velocity at the current time with
:meth:`TeleopMotion.set_velocity` and the hand moves on at that velocity,
inside :data:`WORKSPACE`, until the next command.

The robot observes it as it observes a synthetic motion: skeleton frames at
``frame_hz`` (sample-and-hold between frames) with ``noise_m`` of white noise
per frame (:class:`~sandbox.data.synthetic.tracker.TrackerModel`'s defaults),
without the tracker's jumps.

Use it through the environment::

    obs, info = env.reset(seed=0, options={"source": "teleop"})
    hand = env.unwrapped.motion            # the TeleopMotion of this episode
    hand.set_velocity([-0.2, 0.0, 0.0])    # toward Baxter at 0.2 m/s
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sandbox.data.synthetic.base import HAND_START
from sandbox.envs.human import BODY_DIMS
from sandbox.validation import check_array, check_positive

FloatArray = NDArray[np.float64]

#: Box (m, Baxter's base frame) the teleoperated hand stays in: rows x, y, z; columns low, high.
WORKSPACE = np.array([[0.45, 1.40], [-0.60, 0.70], [-0.30, 0.70]])
#: Fastest hand speed accepted (m/s).
MAX_SPEED = 2.0


class TeleopMotion:
    """A hand that moves at the velocity last commanded, observed through the tracker.

    Parameters
    ----------
    rng : numpy.random.Generator
        Draws the tracker noise (the environment's ``np_random``).
    start : array_like, shape (3,)
        Where the hand starts (m); default the synthetic handovers' start.
    task : str
        Label of the episode (what the human intends is not known): ``"teleop"``.
    frame_hz : float
        Skeleton frame rate of the tracker (Hz).
    noise_m : float
        Standard deviation (m) of the tracker noise per frame (0: none).
    speed : float
        Factor applied to every commanded velocity (the environment's ``speed`` option).

    Attributes
    ----------
    task, source : str
    meta : dict
    now : float
        Latest time (s) at which the hand was placed or measured: commands apply from then.
    """

    def __init__(self, rng: np.random.Generator, start: ArrayLike = HAND_START, *,
                 task: str = "teleop", frame_hz: float = 30.0, noise_m: float = 0.002,
                 speed: float = 1.0) -> None:
        if not isinstance(rng, np.random.Generator):
            raise ValueError(f"rng: expected a numpy.random.Generator, got {type(rng).__name__}")
        start = check_array(start, "start", 1, shape=(3,))
        self.rng, self.task, self.source = rng, str(task), "teleop"
        self.frame_hz = check_positive(frame_hz, "frame_hz")
        self.noise_m = check_positive(noise_m, "noise_m", allow_zero=True)
        self.speed = check_positive(speed, "speed")
        self.meta: dict = {"start": start.copy()}
        self._anchor_t, self._anchor_p = 0.0, np.clip(start, WORKSPACE[:, 0], WORKSPACE[:, 1])
        self._velocity = np.zeros(3)
        self._frames: dict[int, FloatArray] = {}
        self.now = 0.0

    @property
    def duration(self) -> float:
        """Time (s) the hand has been driven so far (the motion has no fixed end)."""
        return self.now

    @property
    def velocity(self) -> FloatArray:
        """The hand's commanded velocity (3,) m/s (after the ``speed`` factor)."""
        return self._velocity.copy()

    def set_velocity(self, velocity: ArrayLike) -> None:
        """Move at ``velocity`` (3,) m/s (times ``speed``) from :attr:`now` on."""
        velocity = check_array(velocity, "velocity", 1, shape=(3,)) * self.speed
        if np.linalg.norm(velocity) > MAX_SPEED:
            raise ValueError(f"velocity: expected a speed <= {MAX_SPEED} m/s, got "
                             f"{np.linalg.norm(velocity):.3g} m/s")
        self._anchor_p = self.position(self.now)
        self._anchor_t = self.now
        self._velocity = velocity

    def position(self, t: float) -> FloatArray:
        """True hand position (3,) m at time ``t`` (s) >= the last command's time."""
        t = float(t)
        self.now = max(self.now, t)
        p = self._anchor_p + self._velocity * max(t - self._anchor_t, 0.0)
        return np.clip(p, WORKSPACE[:, 0], WORKSPACE[:, 1])

    def positions(self, times: list[float]) -> list[FloatArray]:
        """:meth:`position` at each of ``times`` (s), in order."""
        return [self.position(t) for t in times]

    def edges(self, t: float) -> list[tuple[int, int, float]]:
        """``(axis, side, value m)`` of every workspace edge the hand rests on at ``t`` (s)
        while commanded beyond it (side -1: the lower bound, +1: the upper)."""
        p = self._anchor_p + self._velocity * max(float(t) - self._anchor_t, 0.0)
        out = []
        for axis in range(3):
            if p[axis] < WORKSPACE[axis, 0] and self._velocity[axis] < 0:
                out.append((axis, -1, float(WORKSPACE[axis, 0])))
            elif p[axis] > WORKSPACE[axis, 1] and self._velocity[axis] > 0:
                out.append((axis, 1, float(WORKSPACE[axis, 1])))
        return out

    def measurement(self, t: float) -> FloatArray:
        """The tracker's latest frame (3,) m at time ``t`` (s): a noisy sample of the hand."""
        frame = self._frame(t)
        if frame not in self._frames:
            noise = self.rng.normal(0.0, self.noise_m, 3) if self.noise_m else np.zeros(3)
            self._frames = {frame: self.position(max(frame / self.frame_hz, self._anchor_t))
                            + noise}
        return self._frames[frame].copy()

    def frame_time(self, t: float) -> float:
        """Time (s) of the tracker frame :meth:`measurement` gives at ``t`` (s)."""
        return self._frame(t) / self.frame_hz

    def _frame(self, t: float) -> int:
        """Index of the tracker frame current at ``t`` (s)."""
        return int(math.floor(float(t) * self.frame_hz + 1e-9))

    def tracked(self, t: float) -> tuple[FloatArray, float, dict[str, FloatArray | None]]:
        """:meth:`measurement` (3,) m and its :meth:`frame_time` (s) at ``t`` (s), and no
        body modality (as :meth:`sandbox.envs.human.HumanMotion.tracked`)."""
        return self.measurement(t), self.frame_time(t), {}

    def body_measurement(self, name: str, t: float) -> FloatArray:
        """All NaN (dims,): the teleoperated hand has no tracked arm and no EMG."""
        if name not in BODY_DIMS:
            raise ValueError(f"name: expected one of {list(BODY_DIMS)}, got {name!r}")
        return np.full(BODY_DIMS[name], np.nan)

    def scaled(self, speed: float) -> TeleopMotion:
        """A fresh teleoperated hand (same start and tracker) whose commands are ``speed`` x."""
        return TeleopMotion(self.rng, self.meta["start"], task=self.task,
                            frame_hz=self.frame_hz, noise_m=self.noise_m,
                            speed=self.speed * check_positive(speed, "speed"))
