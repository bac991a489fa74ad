"""Paired human/robot demonstrations from task specs: human reach, tracker, robot arm.

:func:`generate` draws every demonstration's random numbers, solves the
robot's inverse kinematics for all handover points in one batch, redraws the
end point of any demonstration whose handover point the arm cannot reach (so a
pairing is never wrong: it meets the hand within ``ik_tol``), and assembles the
:class:`~sandbox.data.demonstration.Demonstration` objects.
"""

from __future__ import annotations

from collections.abc import Sequence

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
from sandbox.data.synthetic.tasks import (
    DemoDraw,
    TaskSpec,
    Variability,
    draw_demo,
    make_reach,
    redraw_end,
)
from sandbox.data.synthetic.tracker import TrackerModel
from sandbox.robot import GRASP_OFFSET
from sandbox.validation import FloatArray, check_integer, check_positive, check_rng


def handover_target(spec: TaskSpec, draw: DemoDraw) -> FloatArray:
    """Where the gripper tip meets the hand (m), shape (3,): reach end + grasp offset."""
    return spec.end + draw.end_shift + spec.branch + GRASP_OFFSET + draw.grasp_shift


def pair_with_robot(
    specs: Sequence[TaskSpec],
    draws: list[DemoDraw],
    var: Variability,
    rng: np.random.Generator,
    *,
    ik_tol: float = 0.01,
    max_redraws: int = 5,
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
        targets = np.array([handover_target(specs[i], draws[i]) for i in todo])
        res = solve_handover(targets, ik_tol)
        q_goal[todo], error[todo] = res.q, res.error
        todo = todo[~res.success]
        if todo.size == 0:
            return draws, q_goal, error
    names = sorted({specs[i].name for i in todo})
    raise ValueError(
        f"tasks {names}: expected handover points Baxter's left arm can reach (IK within "
        f"{ik_tol} m), got {todo.size} still unreachable after {max_redraws} redraws "
        f"(smallest error {error[todo].min():.3f} m); move the task's end point"
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
) -> Demonstration:
    """Assemble one demonstration: clean reach, tracker artefacts, robot trajectory.

    ``meta`` holds ``hand_end`` and ``handover_target`` (m), ``reach_time`` and
    ``robot_time`` (start, end; s), ``divergence_time`` (s; ``None`` unless
    ``branching``) and ``clean_human`` (T, 3) m, the hand before the tracker
    (and ``clean_arm`` (T, 6) m, the arm's, when ``observe`` has ``"arm"``).
    """
    times = sample_times(draw.duration, rate_hz)
    reach = make_reach(spec, draw, var)
    clean = reach_positions(reach, times)
    human, modalities, extra = observe_human(observe, times, clean, tracker, draw.tracker_seed,
                                             arm_model)
    kin = kinematics()
    robot = joint_trajectory(
        times, q_goal, draw.robot_on, draw.robot_off, draw.wobble, (kin.lower, kin.upper)
    )
    meta = {
        "hand_end": reach.end,
        "handover_target": handover_target(spec, draw),
        "reach_time": (draw.t_on, draw.t_off),
        "robot_time": (draw.robot_on, draw.robot_off),
        "divergence_time": draw.t_div if branching else None,
        "clean_human": clean,
        **extra,
    }
    return Demonstration(
        times=times, human=human, robot=robot, task=spec.name, robot_names=ROBOT_NAMES,
        modalities=modalities, source=source, meta=meta,
    )


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
    family : str
        Name recorded in each demonstration's ``source``.
    variability : Variability
        Spreads and timing.
    tracker : TrackerModel, optional
        Tracker artefacts (default: like the recordings, ``TrackerModel()``).
    rate_hz : float
        Row rate (Hz).
    ik_tol : float
        Required gripper position error (m) at the handover point.
    max_redraws : int
        Rounds of end-point redraws for unreachable handover points.
    observe : str or sequence of str
        Observed modalities, ``"hand"`` (default), ``"arm"`` or both (e.g.
        ``"hand,arm"``: ``human`` has 9 columns, hand then arm).
    arm_model : ArmModel, optional
        The human arm (default ``ArmModel()``); used when the arm is observed.

    Returns
    -------
    list of Demonstration
    """
    n, rate_hz, ik_tol, max_redraws = _check_sizes(n_per_task, rng, rate_hz, ik_tol, max_redraws)
    tracker, observe = _check_models(tracker, observe, variability)
    task_of = [spec for spec in specs for _ in range(n)]
    draws = [draw_demo(spec, variability, rng) for spec in task_of]
    draws, q_goal, _ = pair_with_robot(task_of, draws, variability, rng, ik_tol=ik_tol,
                                       max_redraws=max_redraws)
    return [
        build_demo(
            spec, draw, q, var=variability, tracker=tracker, rate_hz=rate_hz,
            source=f"synthetic:{family}[{spec.name}#{i % n}]",
            branching=any(np.any(s.branch) for s in specs), observe=observe, arm_model=arm_model,
        )
        for i, (spec, draw, q) in enumerate(zip(task_of, draws, q_goal, strict=True))
    ]


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
