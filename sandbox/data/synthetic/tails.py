"""What the hand does after the handover in a session (its *tail*), and the session's timing.

A :class:`Tail` holds one demonstration's random numbers for its session's
tail kind (:data:`~sandbox.data.synthetic.session.TAILS`), drawn from a stream
of its own (:func:`tail_rng`, a child of the demonstration's tracker seed), so
the demonstration's other random numbers are those of the session-free data.

Times: ``t_on``, ``t_off`` are the reach's start and end, ``robot_off`` when the
robot arrives; the *meeting* is at ``max(robot_off, t_off)`` (both there,
:func:`meeting_time`). :func:`session_timing` scales every duration and onset
by the session's tempo and makes the recording run on ``hold_s`` (0.4-1.0 s)
after the meeting so the tail is seen (longer for ``drift_back``, whose
retreat must end before the recording does). The kinds
(:func:`tail_positions`, :func:`freeze_row`):

``stop_wait``
    The path is shortened by ``short_m`` (3-8 cm) along the start-end
    direction, in proportion to the path's progress: the hand comes to rest
    ``short_m`` short of its end point and stays there, still (no drift); the
    robot meets it there (:func:`rest_point`).
``linger``
    After ``t_off`` the hand wanders around its end point: two sinusoids
    (0.2-0.6 Hz) along two orthogonal random directions, mixed so that the
    wander's norm never exceeds ``wander_m`` (1-3 cm), faded in over 0.3 s.
``drift_back``
    ``release_s`` (0.1-0.3 s) after the meeting (the release) the hand
    retreats ``retreat_m`` (10-25 cm) toward its start along a minimum-jerk
    profile of ``retreat_s`` (0.5-0.8 s).
``overshoot``
    A minimum-jerk bump along the start-end direction, rising from mid-reach
    to ``over_m`` (3-8 cm) at ``t_off`` and back to 0 ``back_s`` (0.2-0.4 s)
    later: the hand passes its end point and comes back. The robot arrives
    no earlier than 0.05 s after the hand is back.
``freeze``
    The clean hand is today's; the tracker repeats its last frame from
    ``freeze_phase`` (0.7-0.95) of the recording to its end, the whole
    skeleton (hand and arm).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from sandbox.data.synthetic.base import minimum_jerk
from sandbox.data.synthetic.human import Reach, reach_positions, submovements
from sandbox.data.synthetic.session import NO_TAIL, TAILS
from sandbox.data.synthetic.tasks import DemoDraw
from sandbox.validation import FloatArray, check_choice

#: Fade-in (s) of the linger wander after the hand's arrival.
WANDER_FADE_S = 0.3
#: Margin (s) between the overshoot's return and the robot's arrival.
OVERSHOOT_MARGIN_S = 0.05


@dataclass(frozen=True)
class Tail:
    """One demonstration's tail: its kind and random numbers (m, s, Hz).

    Every number is drawn whatever the kind; only the kind's are used.
    """

    kind: str
    hold_s: float
    short_m: float
    wander_m: float
    wander_hz: FloatArray
    wander_axes: FloatArray
    wander_mix: float
    release_s: float
    retreat_m: float
    retreat_s: float
    over_m: float
    back_s: float
    freeze_phase: float


def tail_rng(seed: int) -> np.random.Generator:
    """The tail's generator of a demonstration whose tracker is seeded with ``seed``.

    The second child of ``SeedSequence(seed)`` (the arm's is the first), so
    drawing a tail never changes any other random number.
    """
    return np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(1,)))


def draw_tail(kind: str, rng: np.random.Generator) -> Tail:
    """Draw a tail of ``kind`` (one of :data:`TAILS` or ``"none"``) from ``rng``."""
    check_choice(kind, "tail", (*TAILS, NO_TAIL))
    axes = np.linalg.qr(rng.normal(size=(3, 3)))[0][:, :2].T
    return Tail(
        kind=kind, hold_s=rng.uniform(0.4, 1.0), short_m=rng.uniform(0.03, 0.08),
        wander_m=rng.uniform(0.01, 0.03), wander_hz=rng.uniform(0.2, 0.6, 2),
        wander_axes=axes, wander_mix=rng.uniform(0.0, 0.5 * np.pi),
        release_s=rng.uniform(0.1, 0.3), retreat_m=rng.uniform(0.10, 0.25),
        retreat_s=rng.uniform(0.5, 0.8), over_m=rng.uniform(0.03, 0.08),
        back_s=rng.uniform(0.2, 0.4), freeze_phase=rng.uniform(0.7, 0.95),
    )


def meeting_time(t_off: float, robot_off: float) -> float:
    """When the hand (done at ``t_off``, s) and the robot (``robot_off``, s) have both arrived."""
    return max(float(t_off), float(robot_off))


def meeting_row(times: FloatArray, reach_time: tuple[float, float],
                robot_time: tuple[float, float]) -> int:
    """The first row (index into ``times``, s) at or after the meeting (the last row at most).

    ``reach_time`` and ``robot_time`` are the ``(start, end)`` (s) of a
    demonstration's ``meta``.
    """
    t = meeting_time(reach_time[1], robot_time[1])
    return int(min(np.searchsorted(times, t - 1e-9), len(times) - 1))


def session_timing(draw: DemoDraw, tempo: float, tail: Tail) -> DemoDraw:
    """``draw`` with every time scaled by ``tempo`` and the recording long enough for ``tail``.

    The overshoot moves the robot's arrival to at least
    ``t_off + back_s + OVERSHOOT_MARGIN_S``; a tail other than ``"none"``
    makes the recording last at least ``hold_s`` after the meeting
    (``drift_back``: ``release_s + retreat_s + hold_s / 4``).
    """
    times = {key: tempo * getattr(draw, key)
             for key in ("duration", "t_on", "t_off", "t_div", "robot_on", "robot_off")}
    if tail.kind == "overshoot":
        times["robot_off"] = max(times["robot_off"],
                                 times["t_off"] + tail.back_s + OVERSHOOT_MARGIN_S)
    if tail.kind != NO_TAIL:
        meet = meeting_time(times["t_off"], times["robot_off"])
        run_on = (tail.release_s + tail.retreat_s + tail.hold_s / 4
                  if tail.kind == "drift_back" else tail.hold_s)
        times["duration"] = max(times["duration"], meet + run_on)
    return replace(draw, **times)


def _approach(start: FloatArray, end: FloatArray) -> FloatArray:
    """Unit vector (3,) from the reach's ``start`` to its ``end`` (m, (3,) each)."""
    d = np.asarray(end, dtype=float) - start
    return d / np.linalg.norm(d)


def rest_point(start: FloatArray, end: FloatArray, tail: Tail | None) -> FloatArray:
    """Where the hand is at the handover (m), shape (3,).

    ``end`` (the reach's, (3,) m), or for a ``stop_wait`` tail ``short_m``
    short of it, back toward ``start`` ((3,) m).
    """
    if tail is not None and tail.kind == "stop_wait":
        return end - tail.short_m * _approach(start, end)
    return np.array(end, dtype=float)


def tail_positions(reach: Reach, times: FloatArray, tail: Tail, t_meet: float) -> FloatArray:
    """The clean hand (m), shape (T, 3), of ``reach`` at ``times`` (s) with ``tail``.

    ``t_meet`` (s) is the meeting (:func:`meeting_time`); see the module's
    docstring for each kind. ``"none"`` and ``"freeze"`` give
    :func:`~sandbox.data.synthetic.human.reach_positions` unchanged.
    """
    kind, u = tail.kind, _approach(reach.points[0], reach.end)
    if kind in ("stop_wait", "linger"):
        still = replace(reach, drift=np.zeros(3))
        path = reach_positions(still, times)
        if kind == "stop_wait":
            main, fix = submovements(reach, times)
            progress = (1.0 - reach.correction) * main + reach.correction * fix
            return path - np.outer(progress, tail.short_m * u)
        return path + _wander(times - reach.t_off, tail)
    path = reach_positions(reach, times)
    if kind == "drift_back":
        back = minimum_jerk((times - t_meet - tail.release_s) / tail.retreat_s)
        return path - np.outer(back, tail.retreat_m * u)
    if kind == "overshoot":
        mid = 0.5 * (reach.t_on + reach.t_off)
        rise = minimum_jerk((times - mid) / (reach.t_off - mid))
        fall = minimum_jerk((times - reach.t_off) / tail.back_s)
        return path + np.outer(rise - fall, tail.over_m * u)
    return path


def _wander(hold: FloatArray, tail: Tail) -> FloatArray:
    """The linger wander (T, 3) m at ``hold`` seconds after the arrival (0 before it).

    Its norm is at most ``wander_m``: two sinusoids on orthogonal unit axes
    weighted by ``cos`` and ``sin`` of ``wander_mix``.
    """
    fade = minimum_jerk(hold / WANDER_FADE_S)
    phase = 2.0 * np.pi * np.outer(np.maximum(hold, 0.0), tail.wander_hz)
    weights = np.sin(phase) * np.array([np.cos(tail.wander_mix), np.sin(tail.wander_mix)])
    return tail.wander_m * fade[:, None] * (weights @ tail.wander_axes)


def freeze_row(times: FloatArray, tail: Tail | None) -> int | None:
    """The first row the tracker freezes on (``freeze`` tails; else None).

    The row at ``freeze_phase`` of the recording, at least 1 and at most the
    second-to-last, so at least two rows repeat the frame before it.
    """
    if tail is None or tail.kind != "freeze":
        return None
    t = times[0] + tail.freeze_phase * (times[-1] - times[0])
    return int(np.clip(np.searchsorted(times, t), 1, len(times) - 2))


def frozen(observed: FloatArray, row: int | None) -> FloatArray:
    """``observed`` (T, P) with rows ``row`` on repeating row ``row - 1`` (a new array)."""
    out = np.array(observed, dtype=float)
    if row is not None:
        out[row:] = out[row - 1]
    return out
