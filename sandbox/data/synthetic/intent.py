"""An intent switch: the human starts one task and changes to another mid-motion.

The hand follows task ``a``'s motion until the switch time, then moves to task
``b``'s motion along a minimum-jerk transition of ``blend_s`` seconds (both
motions share one random draw: same start, speed and timing). The robot's
demonstrated motion switches the same way, so it ends at task ``b``'s handover
configuration. The ground truth says which task the human pursues at each
sample: ``a`` before the switch time, ``b`` from it on.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from sandbox.data.demonstration import Demonstration
from sandbox.data.synthetic.arm import ArmModel
from sandbox.data.synthetic.base import ROBOT_NAMES, sample_times
from sandbox.data.synthetic.families import DIVERGING_VARIABILITY, OBJECTS, diverging_specs
from sandbox.data.synthetic.generator import handover_target
from sandbox.data.synthetic.human import reach_positions, switch_paths
from sandbox.data.synthetic.observe import check_observe, observe_human
from sandbox.data.synthetic.robot import joint_trajectory, kinematics, solve_handover
from sandbox.data.synthetic.tasks import DemoDraw, TaskSpec, Variability, draw_demo, make_reach
from sandbox.data.synthetic.tasks import redraw_end as _redraw_end
from sandbox.data.synthetic.tracker import TrackerModel
from sandbox.validation import FloatArray, check_fraction, check_positive, check_rng

#: Families an intent switch can be drawn from.
SWITCH_FAMILIES = ("diverging", "objects")


@dataclass(frozen=True)
class IntentSwitch:
    """Ground truth of an intent-switch demonstration.

    Attributes
    ----------
    tasks : tuple of str
        ``(a, b)``: the task before and after the switch.
    switch_time : float
        When the intent changes (s, from the first sample).
    switch_phase : float
        The same as a fraction of the duration.
    blend_s : float
        Duration (s) of the hand's transition from ``a``'s motion to ``b``'s.
    times : ndarray, shape (T,)
        The demonstration's sample times (s).
    """

    tasks: tuple[str, str]
    switch_time: float
    switch_phase: float
    blend_s: float
    times: FloatArray

    def task_at(self, t: FloatArray) -> np.ndarray:
        """Task pursued at times ``t`` (s), an array of task names of the shape of ``t``."""
        t = np.asarray(t, dtype=float)
        return np.where(t < self.switch_time, self.tasks[0], self.tasks[1])

    @property
    def labels(self) -> np.ndarray:
        """Task pursued at each sample, shape (T,)."""
        return self.task_at(self.times)


def _family_specs(family: str, branch_m: float) -> tuple[dict[str, TaskSpec], Variability]:
    if family == "diverging":
        return {s.name: s for s in diverging_specs(branch_m=branch_m)}, DIVERGING_VARIABILITY
    if family == "objects":
        return {s.name: s for s in OBJECTS}, Variability()
    raise ValueError(f"family: expected one of {list(SWITCH_FAMILIES)}, got {family!r}")


def _solve_pair(
    specs: tuple[TaskSpec, TaskSpec], draw: DemoDraw, var: Variability,
    rng: np.random.Generator, ik_tol: float, max_redraws: int,
) -> tuple[DemoDraw, FloatArray]:
    """Handover configurations (2, 7) of both tasks under one draw (redrawn if unreachable)."""
    for _ in range(max_redraws + 1):
        res = solve_handover(np.array([handover_target(s, draw) for s in specs]), ik_tol)
        if res.success.all():
            return draw, res.q
        draw = _redraw_end(draw, var, rng)
    raise ValueError(
        f"tasks {[s.name for s in specs]}: expected handover points Baxter's left arm can "
        f"reach (IK within {ik_tol} m), got none after {max_redraws} redraws"
    )


def _switched_robot(
    times: FloatArray, q_goal: FloatArray, draw: DemoDraw, t_switch: float, blend_s: float
) -> FloatArray:
    """The robot's motion (T, 7) rad toward ``q_goal[0]``, switching to ``q_goal[1]``."""
    kin = kinematics()
    arms = [
        joint_trajectory(times, q, draw.robot_on, draw.robot_off, draw.wobble,
                         (kin.lower, kin.upper))
        for q in q_goal
    ]
    return switch_paths(arms[0], arms[1], times, t_switch, blend_s)


def intent_switch_demo(
    task_a: str,
    task_b: str,
    switch_phase: float,
    rng: np.random.Generator,
    *,
    family: str = "diverging",
    blend_s: float = 0.3,
    branch_m: float = 0.18,
    tracker: TrackerModel | None = None,
    variability: Variability | None = None,
    rate_hz: float = 100.0,
    ik_tol: float = 0.01,
    max_redraws: int = 5,
    observe: Sequence[str] | str = ("hand",),
    arm_model: ArmModel | None = None,
) -> tuple[Demonstration, IntentSwitch]:
    """A demonstration that follows ``task_a`` and switches to ``task_b`` at ``switch_phase``.

    Parameters
    ----------
    task_a, task_b : str
        Tasks of ``family`` (e.g. ``"left"`` and ``"right"``; ``"box"`` and ``"tape"``).
    switch_phase : float
        When the intent changes, as a fraction of the duration, in (0, 1].
    rng : numpy.random.Generator
        Source of randomness; the same seed gives the same demonstration.
    family : str
        ``"diverging"`` (default) or ``"objects"``.
    blend_s : float
        Duration (s) of the hand's (and robot's) transition to the new motion.
    branch_m : float
        Branch size (m) of the diverging family.
    tracker, variability, rate_hz, ik_tol, max_redraws, observe, arm_model
        As in :func:`sandbox.data.synthetic.generator.generate` (with the arm
        observed, it follows the switching hand).

    Returns
    -------
    demo : Demonstration
        Labelled ``task_b`` (the task the robot completes); ``meta["intent"]``
        holds the ground truth too, ``meta["clean_human"]`` (and ``meta["clean_arm"]``)
        the motion before the tracker.
    truth : IntentSwitch
        Which task the human pursues at which time.
    """
    check_rng(rng)
    pair, default_var = _task_pair(family, branch_m, task_a, task_b)
    switch_phase = check_fraction(switch_phase, "switch_phase")
    blend_s = check_positive(blend_s, "blend_s")
    var = variability or default_var
    tracker = TrackerModel() if tracker is None else tracker
    observe = check_observe(observe)
    draw = draw_demo(pair[1], var, rng)
    draw, q_goal = _solve_pair(pair, draw, var, rng, check_positive(ik_tol, "ik_tol"), max_redraws)
    times = sample_times(draw.duration, check_positive(rate_hz, "rate_hz"))
    truth = IntentSwitch((task_a, task_b), switch_phase * draw.duration, switch_phase, blend_s,
                         times)
    return _switch_demo(pair, draw, var, q_goal, truth, tracker, observe, arm_model), truth


def _task_pair(
    family: str, branch_m: float, task_a: str, task_b: str
) -> tuple[tuple[TaskSpec, TaskSpec], Variability]:
    """The specs of ``task_a`` and ``task_b`` in ``family``, and the family's variability."""
    specs, default_var = _family_specs(family, branch_m)
    for name in (task_a, task_b):
        if name not in specs:
            raise ValueError(f"task: expected one of {list(specs)} ({family}), got {name!r}")
    return (specs[task_a], specs[task_b]), default_var


def _switch_demo(
    pair: tuple[TaskSpec, TaskSpec], draw: DemoDraw, var: Variability, q_goal: FloatArray,
    truth: IntentSwitch, tracker: TrackerModel, observe: tuple[str, ...],
    arm_model: ArmModel | None,
) -> Demonstration:
    """The demonstration of ``truth``: both tasks' motions under ``draw``, switched."""
    times, t_switch, blend_s = truth.times, truth.switch_time, truth.blend_s
    paths = [reach_positions(make_reach(s, draw, var), times) for s in pair]
    clean = switch_paths(paths[0], paths[1], times, t_switch, blend_s)
    human, modalities, extra = observe_human(observe, times, clean, tracker, draw.tracker_seed,
                                             arm_model)
    task_a, task_b = truth.tasks
    return Demonstration(
        times=times, human=human, robot=_switched_robot(times, q_goal, draw, t_switch, blend_s),
        task=task_b, robot_names=ROBOT_NAMES, modalities=modalities,
        source=f"synthetic:intent[{task_a}->{task_b}@{truth.switch_phase:g}]",
        meta={"intent": truth, "clean_human": clean, "handover_target":
              handover_target(pair[1], draw), "hand_end": make_reach(pair[1], draw, var).end,
              **extra},
    )
