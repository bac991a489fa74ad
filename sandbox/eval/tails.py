"""Emulated motion tails: what the hand does after the meeting, written onto recorded trials.

Recording sessions differ by what the hand does once the partners have met (issue 21): it
waits, lingers, drifts back, stops short of where it would have gone, overshoots, or the
tracker freezes. The shared recordings have one such behaviour; :func:`emulate_tail` rewrites
a trial's human positions after its *meeting* (the end of its motion, both partners arrived:
:func:`~sandbox.core.fitting.motion_end` on the training version of the trial) as one of
:data:`KINDS`:

``none``
    unmodified.
``hold``
    the hand (and the arm) held still at the meeting pose, 1.5 mm noise, to the end.
``linger``
    ``hold``, and the recording extended by 1.5 s (the robot holds its last pose; signal
    modalities hold their last value).
``drift_back``
    ``hold`` for 0.1-0.3 s, then 10-25 cm back toward the start (minimum jerk over 0.6 s).
``stop_short``
    the approach ends 3-8 cm short of where it did along the start-to-meeting direction
    (ramped in, minimum jerk, over the second half of the motion), then waits there.
``overshoot``
    past the meeting point by 4-8 cm along that direction in 0.25 s and back in 0.25 s,
    then ``hold``.
``freeze``
    from a time in the last 30 % of the recording the position rows repeat the last valid
    one (a tracker that froze).

Position modalities are the first ``3 x n`` human dims (the recordings' hand, then the
arm's elbow and shoulder); a displacement moves the hand by its full size, the second point
by 0.6 of it and any later one by 0.2 (:data:`POINT_GAINS`), as an arm would follow the hand.
At most three points are moved. Signal modalities (EMG) are left as recorded.

:func:`with_tail` writes a tail onto every test stream of a leave-one-out (a tail the
training demonstrations never had) or onto the training demonstrations too (a session
whose every trial has it); trial ``i`` draws its numbers from
``np.random.default_rng([KINDS.index(kind), i])``, the same for its two versions.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from sandbox.core.fitting import motion_end
from sandbox.data.synthetic.base import minimum_jerk
from sandbox.validation import FloatArray, check_choice

__all__ = ["KINDS", "POINT_GAINS", "emulate_tail", "with_tail"]

#: The tails :func:`emulate_tail` writes (``"none"`` leaves a trial as it is).
KINDS = ("none", "hold", "linger", "drift_back", "stop_short", "overshoot", "freeze")
#: Share of a displacement that moves each 3-D position point: hand, elbow, shoulder.
POINT_GAINS = (1.0, 0.6, 0.2)
#: Standard deviation (m) of the noise on a held position.
HOLD_NOISE_M = 0.0015
#: How long (s) ``linger`` extends a recording.
LINGER_S = 1.5


def _n_position(demo: Any) -> int:
    """Number of position dims moved (whole 3-D points, at most three)."""
    n = sum(m.size for m in demo.modalities if m.kind == "position")
    n = min(3 * len(POINT_GAINS), n - n % 3)
    if n < 3 or demo.modalities[0].kind != "position":
        raise ValueError(f"emulate_tail: expected the trial's first modality to be a 3-D "
                         f"position (the hand), got {[m.name for m in demo.modalities]}")
    return n


def emulate_tail(demo: Any, kind: str, rng: np.random.Generator, *, truth: Any = None,
                 settle_tol: float | None = 0.05, arrive_tol: float | None = 0.02) -> Any:
    """``demo`` with its positions after the meeting rewritten as tail ``kind`` (a new trial).

    Parameters
    ----------
    demo : Demonstration
        A trial with robot and human dims; its first modality the hand (m).
    kind : str
        One of :data:`KINDS`.
    rng : numpy.random.Generator
        The tail's random numbers (sizes, times, noise).
    truth : Demonstration, optional
        The same trial as the training set has it (smoothed; default ``demo``): its motion's
        end is the meeting (:func:`~sandbox.core.fitting.motion_end` with ``settle_tol``
        (rad) and ``arrive_tol`` (m), the model's tolerances). Same times as ``demo``.

    Returns
    -------
    Demonstration
        ``demo`` itself for ``"none"``; otherwise a copy (``demo`` is never changed).
    """
    check_choice(kind, "tail", KINDS)
    if kind == "none":
        return demo
    truth = demo if truth is None else truth
    if len(truth.times) != len(demo.times):
        raise ValueError(f"emulate_tail: expected truth with the trial's {len(demo.times)} "
                         f"samples, got {len(truth.times)}")
    n = _n_position(demo)
    t = np.asarray(demo.times) - demo.times[0]
    i_m = motion_end(t, np.asarray(demo.robot), settle_tol, np.asarray(truth.human), arrive_tol)
    human = np.array(demo.human, dtype=np.float64)
    pos = human[:, :n]
    valid = np.flatnonzero(np.isfinite(pos).all(axis=1))
    if valid.size == 0:
        raise ValueError("emulate_tail: expected some rows with every position finite, got none")
    here = pos[valid[valid <= i_m][-1] if (valid <= i_m).any() else valid[0]].copy()
    start = pos[np.isfinite(pos[:, :3]).all(axis=1)][0, :3]
    gain = np.repeat(np.array(POINT_GAINS[: n // 3]), 3)
    ctx = _Context(t, i_m, pos, here, start, gain, rng)
    if kind == "linger":
        return _linger(demo, human, ctx)
    _WRITERS[kind](ctx)
    human[:, :n] = ctx.pos
    return replace(demo, human=human)


class _Context:
    """What every tail writer reads: times (s), the meeting index, positions (m), the
    meeting pose, the start, the per-dim gains, the generator."""

    def __init__(self, t, i_m, pos, here, start, gain, rng) -> None:
        self.t, self.t_m, self.pos, self.here, self.gain, self.rng = t, t[i_m], pos, here, gain, rng
        self.after = t > self.t_m
        u = here[:3] - start
        self.u = u / max(float(np.linalg.norm(u)), 1e-6)
        self.start = start

    def noise(self, rows: int) -> FloatArray:
        return self.rng.normal(0.0, HOLD_NOISE_M, (rows, self.pos.shape[1]))

    def along(self, direction: FloatArray) -> FloatArray:
        """A displacement of the hand along ``direction`` (3,) spread over the points."""
        return np.tile(direction, self.pos.shape[1] // 3) * self.gain


def _hold(c: _Context) -> None:
    c.pos[c.after] = c.here + c.noise(int(c.after.sum()))


def _drift_back(c: _Context) -> None:
    wait, dist = c.rng.uniform(0.1, 0.3), c.rng.uniform(0.10, 0.25)
    s = minimum_jerk((c.t[c.after] - c.t_m - wait) / 0.6)[:, None]
    away = c.start - c.here[:3]
    away = away / max(float(np.linalg.norm(away)), 1e-6) * dist
    c.pos[c.after] = c.here + s * c.along(away) + c.noise(int(c.after.sum()))


def _stop_short(c: _Context) -> None:
    short = c.rng.uniform(0.03, 0.08)
    ramp = minimum_jerk((c.t - 0.5 * c.t_m) / max(0.5 * c.t_m, 1e-9))[:, None]
    off = c.along(-short * c.u)
    c.pos[:] = c.pos + ramp * off
    c.pos[c.after] = c.here + off + c.noise(int(c.after.sum()))


def _overshoot(c: _Context) -> None:
    over = c.rng.uniform(0.04, 0.08)
    x = c.t[c.after] - c.t_m
    s = np.where(x < 0.25, minimum_jerk(x / 0.25), 1 - minimum_jerk((x - 0.25) / 0.25))[:, None]
    c.pos[c.after] = c.here + s * c.along(over * c.u) + c.noise(int(c.after.sum()))


def _freeze(c: _Context) -> None:
    i_f = int(np.searchsorted(c.t, c.rng.uniform(0.7, 1.0) * c.t[-1]))
    ok = np.flatnonzero(np.isfinite(c.pos[: i_f + 1]).all(axis=1))
    c.pos[i_f:] = c.pos[ok[-1]]


_WRITERS = {"hold": _hold, "drift_back": _drift_back, "stop_short": _stop_short,
            "overshoot": _overshoot, "freeze": _freeze}


def _linger(demo: Any, human: FloatArray, c: _Context) -> Any:
    _hold(c)
    human[:, : c.pos.shape[1]] = c.pos
    dt = float(np.median(np.diff(c.t)))
    extra = np.arange(1, int(LINGER_S / dt) + 1) * dt + c.t[-1]
    more = np.repeat(human[-1:], extra.size, axis=0)
    more[:, : c.pos.shape[1]] = c.here + c.noise(extra.size)
    robot = np.asarray(demo.robot)
    return replace(demo, times=np.r_[demo.times, extra + demo.times[0]],
                   human=np.vstack([human, more]),
                   robot=np.vstack([robot, np.repeat(robot[-1:], extra.size, axis=0)]))


def with_tail(train: Sequence[Any], test: Sequence[Any], kind: str, *,
              in_training: bool = False, settle_tol: float | None = 0.05,
              arrive_tol: float | None = 0.02) -> tuple[list, list]:
    """A leave-one-out's trials with tail ``kind`` written onto them.

    ``train[i]`` and ``test[i]`` are the same trial (smoothed, and the causal test stream);
    every test stream gets the tail, its meeting found on ``train[i]``; with ``in_training``
    the training versions get it too (same numbers), as if the whole session had it.
    Returns new lists ``(train, test)``.
    """
    check_choice(kind, "tail", KINDS)
    if len(train) != len(test):
        raise ValueError(f"with_tail: expected as many test streams as trials, got "
                         f"{len(test)} and {len(train)}")
    tol = {"settle_tol": settle_tol, "arrive_tol": arrive_tol}
    k = KINDS.index(kind)
    new_test = [emulate_tail(d, kind, np.random.default_rng([k, i]), truth=train[i], **tol)
                for i, d in enumerate(test)]
    new_train = ([emulate_tail(d, kind, np.random.default_rng([k, i]), **tol)
                  for i, d in enumerate(train)] if in_training else list(train))
    return new_train, new_test
