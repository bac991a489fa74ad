"""Paired human/robot demonstrations from task specs: human reach, tracker, robot arm.

:func:`generate` draws every demonstration's random numbers, solves the
robot's inverse kinematics for all handover points in one batch, redraws the
end point of any demonstration whose handover point the arm cannot reach (so a
pairing is never wrong: it meets the hand within ``ik_tol``), and assembles the
:class:`~sandbox.data.demonstration.Demonstration` objects. A *session*
(:mod:`sandbox.data.synthetic.session`) changes the tracker's frame, where the
fingertip meets the hand, the tempo and the motion's tail
(:mod:`sandbox.data.synthetic.tails`); without one (``session=None``) the
demonstrations are today's, bit for bit.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from sandbox.data.demonstration import Demonstration
from sandbox.data.synthetic.arm import ArmModel
from sandbox.data.synthetic.base import (
    ROBOT_NAMES,
    sample_times,
)
from sandbox.data.synthetic.human import reach_positions
from sandbox.data.synthetic.observe import check_observe, observe_human
from sandbox.data.synthetic.robot import (
    joint_trajectory,
    kinematics,
    solve_handover,
)
from sandbox.data.synthetic.session import Session, as_session
from sandbox.data.synthetic.tails import (
    Tail,
    draw_tail,
    freeze_row,
    frozen,
    meeting_row,
    meeting_time,
    rest_point,
    session_timing,
    tail_positions,
    tail_rng,
)
from sandbox.data.synthetic.tasks import (
    DemoDraw,
    TaskSpec,
    Variability,
    draw_demo,
    make_reach,
    redraw_end,
)
from sandbox.data.synthetic.tracker import TrackerModel
from sandbox.robot import GRASP_OFFSET, TIP_LINK
from sandbox.validation import FloatArray, check_integer, check_positive, check_rng


def handover_target(spec: TaskSpec, draw: DemoDraw, session: Session | None = None,
                    tail: Tail | None = None) -> FloatArray:
    """Where the gripper tip meets the hand (m), shape (3,).

    Without a session: the reach's end + :data:`~sandbox.robot.GRASP_OFFSET` +
    the draw's ``grasp_shift``. With one: where the true hand rests at the
    handover (:func:`~sandbox.data.synthetic.tails.rest_point`: a
    ``stop_wait`` tail stops short) + ``session.object_offset`` + ``grasp_shift``.
    """
    if session is None:
        return spec.end + draw.end_shift + spec.branch + GRASP_OFFSET + draw.grasp_shift
    rest = rest_point(draw.start, spec.end + draw.end_shift + spec.branch, tail)
    return rest + session.object_offset + draw.grasp_shift


def pair_with_robot(
    specs: Sequence[TaskSpec],
    draws: list[DemoDraw],
    var: Variability,
    rng: np.random.Generator,
    *,
    ik_tol: float = 0.01,
    max_redraws: int = 5,
    session: Session | None = None,
    tails: Sequence[Tail] | None = None,
) -> tuple[list[DemoDraw], FloatArray, FloatArray]:
    """Solve the handover configurations of all demonstrations in batches.

    Parameters
    ----------
    specs : sequence of TaskSpec
        The task of each demonstration (same length as ``draws``).
    draws : list of DemoDraw
        Their random numbers.
    var : Variability
        Used to redraw an unreachable end point.
    rng : numpy.random.Generator
        Source of the redraws.
    ik_tol : float
        Required gripper position error (m).
    max_redraws : int
        Redraw rounds before giving up.
    session, tails : Session and sequence of Tail, optional
        The recording session and each demonstration's tail (:func:`handover_target`).

    Returns
    -------
    draws : list of DemoDraw
        The draws, some with a redrawn end point.
    q_goal : ndarray, shape (n, 7)
        Handover configurations (rad).
    error : ndarray, shape (n,)
        Gripper position error (m) at the handover point, all <= ``ik_tol``.

    Raises
    ------
    ValueError
        If some task's handover point stays out of reach after ``max_redraws``.
    """
    draws = list(draws)
    q_goal, error = np.zeros((len(draws), 7)), np.full(len(draws), np.inf)
    todo = np.arange(len(draws))
    for round_ in range(max_redraws + 1):
        if round_:
            for i in todo:
                draws[i] = redraw_end(draws[i], var, rng)
        tail_of = [None] * len(draws) if tails is None else tails
        res = solve_handover(np.array([handover_target(specs[i], draws[i], session, tail_of[i])
                                       for i in todo]), ik_tol)
        q_goal[todo], error[todo] = res.q, res.error
        todo = todo[~res.success]
        if todo.size == 0:
            return draws, q_goal, error
    raise _unreachable(sorted({specs[i].name for i in todo}), todo.size, error[todo].min(),
                       ik_tol, max_redraws)


def _unreachable(names: list[str], n: int, smallest: float, ik_tol: float,
                 max_redraws: int) -> ValueError:
    """The error of :func:`pair_with_robot` when ``n`` handover points of tasks ``names``
    stay out of reach (``smallest``: the smallest error, m)."""
    return ValueError(
        f"tasks {names}: expected handover points Baxter's left arm can reach (IK within "
        f"{ik_tol} m), got {n} still unreachable after {max_redraws} redraws "
        f"(smallest error {smallest:.3f} m); move the task's end point"
    )


def build_demo(
    spec: TaskSpec,
    draw: DemoDraw,
    q_goal: FloatArray,
    *,
    var: Variability,
    tracker: TrackerModel,
    rate_hz: float,
    source: str,
    branching: bool = False,
    observe: tuple[str, ...] = ("hand",),
    arm_model: ArmModel | None = None,
    session: Session | None = None,
    tail: Tail | None = None,
) -> Demonstration:
    """Assemble one demonstration: clean reach, tracker artefacts, robot trajectory.

    ``meta`` holds ``hand_end`` and ``handover_target`` (m), ``reach_time`` and
    ``robot_time`` (start, end; s), ``divergence_time`` (s; ``None`` unless
    ``branching``) and ``clean_human`` (T, 3) m, the true hand before the
    tracker (and ``clean_arm`` (T, 6) m, the arm's, when ``observe`` has
    ``"arm"``). With a ``session`` (and its ``tail``; ``draw`` already timed by
    :func:`~sandbox.data.synthetic.tails.session_timing`) the clean hand has the
    tail, the tracker sees it in the session's frame, and ``meta`` adds
    :func:`session_meta`'s keys.
    """
    times = sample_times(draw.duration, rate_hz)
    reach = make_reach(spec, draw, var)
    if session is None:
        clean = reach_positions(reach, times)
    else:
        clean = tail_positions(reach, times, tail, meeting_time(draw.t_off, draw.robot_off))
    human, modalities, extra = observe_human(
        observe, times, clean, tracker, draw.tracker_seed, arm_model,
        frame=None if session is None else session.to_tracker)
    kin = kinematics()
    robot = joint_trajectory(
        times, q_goal, draw.robot_on, draw.robot_off, draw.wobble, (kin.lower, kin.upper)
    )
    meta = {
        "hand_end": reach.end,
        "handover_target": handover_target(spec, draw, session, tail),
        "reach_time": (draw.t_on, draw.t_off),
        "robot_time": (draw.robot_on, draw.robot_off),
        "divergence_time": draw.t_div if branching else None,
        "clean_human": clean,
        **extra,
    }
    if session is not None:
        human = frozen(human, freeze_row(times, tail))
        meta.update(session_meta(session, times, clean, robot, draw))
    return Demonstration(
        times=times, human=human, robot=robot, task=spec.name, robot_names=ROBOT_NAMES,
        modalities=modalities, source=source, meta=meta,
    )


def session_meta(session: Session, times: FloatArray, clean: FloatArray, robot: FloatArray,
                 draw: DemoDraw) -> dict[str, Any]:
    """The ``meta`` a session adds to a demonstration.

    Parameters
    ----------
    session : Session
        The session.
    times : ndarray, shape (T,)
        Row times (s).
    clean : ndarray, shape (T, 3)
        The true hand (m, Baxter's base frame).
    robot : ndarray, shape (T, 7)
        The robot's joints (rad).
    draw : DemoDraw
        The demonstration's (timed) draw.

    Returns
    -------
    dict
        ``tracked_clean`` (T, 3) m: the true hand in the tracker's frame (what a
        noiseless tracker reports); ``session``: ``session.to_dict()``;
        ``meeting_time`` (s): the first row at or after both the hand and the
        robot have arrived; ``meeting_offset`` (3,) m: the fingertip
        (:data:`~sandbox.robot.TIP_LINK`) there minus ``tracked_clean`` there,
        the offset a model of this session should learn.
    """
    tracked = session.to_tracker(clean)
    row = meeting_row(times, (draw.t_on, draw.t_off), (draw.robot_on, draw.robot_off))
    tip = kinematics().fk(robot[row], link=TIP_LINK)
    return {"tracked_clean": tracked, "session": session.to_dict(),
            "meeting_time": float(times[row]), "meeting_offset": tip - tracked[row]}


def generate(
    specs: Sequence[TaskSpec],
    n_per_task: int,
    rng: np.random.Generator,
    *,
    family: str,
    variability: Variability,
    tracker: TrackerModel | None = None,
    rate_hz: float = 100.0,
    ik_tol: float = 0.01,
    max_redraws: int = 5,
    observe: Sequence[str] | str = ("hand",),
    arm_model: ArmModel | None = None,
    session: Session | int | None = None,
) -> list[Demonstration]:
    """``n_per_task`` paired demonstrations of every task in ``specs``, grouped by task.

    Parameters
    ----------
    specs : sequence of TaskSpec
        The tasks, in output order.
    n_per_task : int
        Demonstrations per task (>= 1).
    rng : numpy.random.Generator
        Source of randomness; the same seed gives the same demonstrations.
    family, variability : str, Variability
        Name recorded in each demonstration's ``source``; spreads and timing.
    tracker : TrackerModel, optional
        Tracker artefacts (default: like the recordings, ``TrackerModel()``).
    rate_hz, ik_tol, max_redraws : float, float, int
        Row rate (Hz); required gripper position error (m) at the handover
        point; rounds of end-point redraws for unreachable handover points.
    observe : str or sequence of str
        Observed modalities, ``"hand"`` (default), ``"arm"`` or both (e.g.
        ``"hand,arm"``: ``human`` has 9 columns, hand then arm).
    arm_model : ArmModel, optional
        The human arm (default ``ArmModel()``); used when the arm is observed.
    session : Session or int, optional
        The recording session (an integer >= 0:
        :func:`~sandbox.data.synthetic.session.draw_session` of it); None
        (default): today's data, bit for bit (:func:`session_draws`).

    Returns
    -------
    list of Demonstration
    """
    n, rate_hz, ik_tol, max_redraws = _check_sizes(n_per_task, rng, rate_hz, ik_tol, max_redraws)
    tracker, observe = _check_models(tracker, observe, variability)
    session = as_session(session)
    task_of = [spec for spec in specs for _ in range(n)]
    draws, tails = session_draws([draw_demo(spec, variability, rng) for spec in task_of], session)
    draws, q_goal, _ = pair_with_robot(task_of, draws, variability, rng, ik_tol=ik_tol,
                                       max_redraws=max_redraws, session=session, tails=tails)
    branching = any(np.any(s.branch) for s in specs)
    return [
        build_demo(spec, draw, q, var=variability, tracker=tracker, rate_hz=rate_hz,
                   source=f"synthetic:{family}[{spec.name}#{i % n}]", branching=branching,
                   observe=observe, arm_model=arm_model, session=session, tail=tail)
        for i, (spec, draw, q, tail) in enumerate(zip(task_of, draws, q_goal, tails, strict=True))
    ]


def session_draws(draws: list[DemoDraw], session: Session | None
                  ) -> tuple[list[DemoDraw], list[Tail | None]]:
    """The draws timed for ``session`` and their tails (None: the draws and no tails).

    Each tail comes from its own stream (:func:`~sandbox.data.synthetic.tails.tail_rng`
    of the draw's tracker seed) and the timing only rescales the draw's times
    (:func:`~sandbox.data.synthetic.tails.session_timing`), so the other random
    numbers of the demonstrations are those of ``session=None``.
    """
    if session is None:
        return draws, [None] * len(draws)
    tails = [draw_tail(session.tail, tail_rng(d.tracker_seed)) for d in draws]
    return [session_timing(d, session.tempo, t) for d, t in zip(draws, tails, strict=True)], tails


def _check_sizes(n_per_task, rng, rate_hz, ik_tol, max_redraws) -> tuple[int, float, float, int]:
    """:func:`generate`'s counts and rates, checked: ``(n_per_task, rate_hz, ik_tol,
    max_redraws)``; ``ValueError`` on a bad one, or on ``rng`` not a Generator."""
    n = check_integer(n_per_task, "n_per_task", 1)
    check_rng(rng)
    rate_hz = check_positive(rate_hz, "rate_hz")
    ik_tol = check_positive(ik_tol, "ik_tol")
    return n, rate_hz, ik_tol, check_integer(max_redraws, "max_redraws", 0)


def _check_models(
    tracker: TrackerModel | None, observe: Sequence[str] | str, variability: Variability
) -> tuple[TrackerModel, tuple[str, ...]]:
    """:func:`generate`'s tracker (default ``TrackerModel()``) and observed modalities,
    checked with its variability; ``ValueError`` on a bad one."""
    tracker = TrackerModel() if tracker is None else tracker
    observe = check_observe(observe)
    if not isinstance(tracker, TrackerModel) or not isinstance(variability, Variability):
        raise ValueError("tracker, variability: expected a TrackerModel and a Variability")
    return tracker, observe
