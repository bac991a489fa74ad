"""Out-of-distribution handovers: motions a model of a training family has never seen.

Kept apart from the training families (:mod:`sandbox.data.synthetic.families`):
nothing here is in :data:`~sandbox.data.synthetic.DATASETS`, and every motion is
drawn from a child of the given generator, so an OOD set never repeats a
training demonstration of the same seed. Each family starts from ordinary
draws of a *base* family (``"diverging"``, default, or ``"objects"``: start,
end, timing, tracker seed, the paired Baxter motion) and changes one thing:

``pause``
    Hesitation mid-reach: the hand slows to a stop between 30 % and 60 % of
    its reach, holds still for 0.8-1.5 s, then goes on (a smooth time warp,
    0.15 s ramps). The robot's paired motion waits with it. Labelled as the
    base task.
``speed``
    A speed outside the demos' range: the whole draw is retimed so that its
    duration lies outside the base family's duration clip
    (:attr:`~sandbox.data.synthetic.tasks.Variability.duration_range`, every
    demo's duration is inside it): 1.15-1.5 times its upper end (slow, even
    trials) or 0.55-0.75 times its lower end (fast, odd trials). Labelled as
    the base task.
``endpoint``
    An endpoint outside every task: the motion starts like a base task and,
    from its divergence time, veers to an end at least ``margin_m`` (0.12 m)
    and 4 end-point standard deviations from every task's mean end, reachable
    by Baxter (the robot meets it there). Labelled ``"endpoint"``.
``other``
    A motion of another task family: the objects family's handovers for a
    diverging base, the diverging family's for an objects base (their own
    tasks, paths and timing). Labelled with those tasks.
``still``
    A motionless hand: it stays where the reach would start for the whole
    recording (the base draw's duration), while the robot makes its usual
    paired motion. Labelled ``"still"``.

Each demonstration has the training sets' format (:class:`Demonstration`,
the same columns, tracker artefacts, optional arm) and ``meta``: ``ood``
(the family), ``base``, ``handover_time`` (s, when the hand and the robot
meet, or would have met: the moment an OOD motion should be flagged before),
``clean_human`` (T, 3) m, and per family ``pause_time`` (start, end; s, the
stretch of zero speed), ``speed_factor`` (new duration / drawn one) or
``odd_end`` (m).

Examples
--------
>>> import numpy as np
>>> from sandbox.data.synthetic.ood import ood_demos
>>> demos = ood_demos("pause", 1, np.random.default_rng(0), base="objects")
>>> [d.task for d in demos], demos[0].meta["ood"]
(['box', 'glasses_case', 'tape'], 'pause')
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from sandbox.data.demonstration import Demonstration
from sandbox.data.synthetic.arm import ArmModel
from sandbox.data.synthetic.base import ROBOT_NAMES, child_rng, minimum_jerk, sample_times
from sandbox.data.synthetic.families import (
    DIVERGING_VARIABILITY,
    OBJECTS,
    diverging_demos,
    diverging_specs,
    objects_demos,
)
from sandbox.data.synthetic.generator import pair_with_robot
from sandbox.data.synthetic.human import reach_positions
from sandbox.data.synthetic.observe import check_observe, observe_human
from sandbox.data.synthetic.robot import joint_trajectory, kinematics, solve_handover
from sandbox.data.synthetic.tasks import DemoDraw, TaskSpec, Variability, draw_demo, make_reach
from sandbox.data.synthetic.tracker import TrackerModel
from sandbox.robot import GRASP_OFFSET
from sandbox.validation import FloatArray, check_choice, check_integer, check_rng

#: The out-of-distribution families, in the order of the module docstring.
OOD_FAMILIES = ("pause", "speed", "endpoint", "other", "still")
#: Training families an OOD family can start from.
BASES = ("diverging", "objects")
#: Range (s) of a pause's hold, and the length (s) of each of its ramps.
PAUSE_S, PAUSE_RAMP_S = (0.8, 1.5), 0.15
#: Where (fraction of the reach) a pause starts.
PAUSE_AT = (0.3, 0.6)
#: Slow durations: this range times the duration clip's upper end; fast: its lower end.
SLOW, FAST = (1.15, 1.5), (0.55, 0.75)
#: Least distance (m) of an odd endpoint from every task's mean end, and in end-point stds.
MARGIN_M, MARGIN_STD = 0.12, 4.0


def base_family(base: str) -> tuple[tuple[TaskSpec, ...], Variability]:
    """The task specs and variability of a base family (``"diverging"`` or ``"objects"``)."""
    check_choice(base, "base", BASES)
    if base == "diverging":
        return diverging_specs(), DIVERGING_VARIABILITY
    return OBJECTS, Variability()


def parse_name(name: str) -> tuple[str, str]:
    """``"pause"`` -> ``("pause", "diverging")``; ``"pause@objects"`` -> ``("pause", "objects")``.

    The name after ``synthetic-ood:`` (:func:`sandbox.data.datasets.load_dataset`);
    a bad family or base is a ``ValueError`` listing the names.
    """
    family, _, base = str(name).partition("@")
    if family not in OOD_FAMILIES or (base and base not in BASES):
        names = ", ".join(OOD_FAMILIES)
        raise ValueError(f"data: expected synthetic-ood:FAMILY or synthetic-ood:FAMILY@BASE "
                         f"(FAMILY one of {names}; BASE one of {', '.join(BASES)}), got "
                         f"'synthetic-ood:{str(name)[:60]}'")
    return family, base or "diverging"


def ood_demos(
    family: str,
    n_per_task: int,
    rng: np.random.Generator,
    *,
    base: str = "diverging",
    observe: Sequence[str] | str = ("hand",),
    tracker: TrackerModel | None = None,
    rate_hz: float = 100.0,
    ik_tol: float = 0.01,
    arm_model: ArmModel | None = None,
) -> list[Demonstration]:
    """Out-of-distribution demonstrations of one family (module docstring).

    Parameters
    ----------
    family : str
        One of :data:`OOD_FAMILIES`.
    n_per_task : int
        Demonstrations per task of the base family (``"other"``: per task of
        the other family), >= 1.
    rng : numpy.random.Generator
        Source of randomness (a child of it is used: ``rng``'s own stream is
        untouched); the same seed gives the same demonstrations.
    base : str
        The training family the motions are unusual for: ``"diverging"`` or ``"objects"``.
    observe, tracker, rate_hz, ik_tol, arm_model
        As in :func:`sandbox.data.synthetic.generator.generate`.

    Returns
    -------
    list of Demonstration
        Grouped by base task; ``source`` is ``synthetic-ood:FAMILY[TASK#i]``.
    """
    check_choice(family, "family", OOD_FAMILIES)
    base_family(base)
    n = check_integer(n_per_task, "n_per_task", 1)
    rng = child_rng(check_rng(rng))
    observe = check_observe(observe)
    tracker = TrackerModel() if tracker is None else tracker
    if family == "other":
        make = objects_demos if base == "diverging" else diverging_demos
        demos = make(n, rng, tracker=tracker, rate_hz=rate_hz, ik_tol=ik_tol, observe=observe,
                     arm_model=arm_model)
        return [_relabel(d, family, base) for d in demos]
    return _changed(family, base, n, rng, observe, tracker, rate_hz, ik_tol, arm_model)


def _changed(family: str, base: str, n: int, rng: np.random.Generator,
             observe: tuple[str, ...], tracker: TrackerModel, rate_hz: float, ik_tol: float,
             arm_model: ArmModel | None) -> list[Demonstration]:
    """``n`` draws per base task, each changed as ``family`` says (all but ``"other"``)."""
    specs, var = base_family(base)
    task_of = [s for s in specs for _ in range(n)]
    draws = [draw_demo(s, var, rng) for s in task_of]
    if family == "endpoint":
        task_of = _odd_specs(task_of, specs, var, rng, ik_tol)
    draws, q_goal, _ = pair_with_robot(task_of, draws, var, rng, ik_tol=ik_tol)
    out = []
    for i, (spec, draw, q) in enumerate(zip(task_of, draws, q_goal, strict=True)):
        timed, warp, extra = _timing(family, draw, var, rng, i)
        if family == "endpoint":
            extra["odd_end"] = spec.end + spec.branch
        demo = _build(spec, timed, q, var, warp, observe, tracker, rate_hz, arm_model,
                      still=family == "still")
        source = f"synthetic-ood:{family}[{spec.name}#{i % n}]"
        label = "still" if family == "still" else spec.name
        out.append(demo.replace(task=label, source=source,
                                meta={**demo.meta, "ood": family, "base": base, **extra}))
    return out


def _relabel(demo: Demonstration, family: str, base: str) -> Demonstration:
    """A demonstration of the other family, renamed and given the OOD ``meta``."""
    meta = dict(demo.meta)
    meet = max(meta["reach_time"][1], meta["robot_time"][1])
    name = demo.source.split("[", 1)[1]
    return demo.replace(source=f"synthetic-ood:{family}[{name}",
                        meta={**meta, "ood": family, "base": base, "handover_time": float(meet)})


def _timing(family: str, draw: DemoDraw, var: Variability, rng: np.random.Generator,
            i: int) -> tuple[DemoDraw, tuple[float, float, float] | None, dict]:
    """The draw retimed for ``family``, the pause (start, hold, ramp; s) and extra ``meta``."""
    if family == "speed":
        lo, hi = var.duration_range
        new = hi * rng.uniform(*SLOW) if i % 2 == 0 else lo * rng.uniform(*FAST)
        factor = new / draw.duration
        return _scaled(draw, factor), None, {"speed_factor": float(factor)}
    if family == "pause":
        start = draw.t_on + rng.uniform(*PAUSE_AT) * (draw.t_off - draw.t_on)
        hold = rng.uniform(*PAUSE_S)
        still = (float(start + PAUSE_RAMP_S), float(start + hold))
        return draw, (start, hold, PAUSE_RAMP_S), {"pause_time": still}
    return draw, None, {}


def _scaled(draw: DemoDraw, factor: float) -> DemoDraw:
    """``draw`` with its duration and every onset multiplied by ``factor``."""
    keys = ("duration", "t_on", "t_off", "t_div", "robot_on", "robot_off")
    return replace(draw, **{k: getattr(draw, k) * factor for k in keys})


def pause_warp(times: FloatArray, start: float, hold: float, ramp: float) -> FloatArray:
    """Motion time of each row time (s): a clock that slows to a stop at ``start``.

    The clock's rate falls from 1 to 0 over ``ramp`` seconds from ``start``,
    stays 0 for ``hold - ramp`` seconds and rises back to 1 over ``ramp``
    seconds (minimum-jerk ramps): the hand moves on its path until ``start``,
    stands still, and goes on; the motion ends ``hold`` seconds later.
    """
    t = np.asarray(times, dtype=np.float64)
    down = minimum_jerk((t - start) / ramp)
    up = minimum_jerk((t - start - hold) / ramp)
    rate = 1.0 - down + up
    lost = np.concatenate([[0.0], np.cumsum(0.5 * (2.0 - rate[1:] - rate[:-1]) * np.diff(t))])
    return t - lost


def _build(spec: TaskSpec, draw: DemoDraw, q_goal: FloatArray, var: Variability,
           pause: tuple[float, float, float] | None, observe: tuple[str, ...],
           tracker: TrackerModel, rate_hz: float, arm_model: ArmModel | None, *,
           still: bool = False) -> Demonstration:
    """One OOD demonstration: the (warped) clean reach, the tracker, the paired robot."""
    extra_s = 0.0 if pause is None else pause[1]
    times = sample_times(draw.duration + extra_s, rate_hz)
    clock = times if pause is None else pause_warp(times, *pause)
    reach = make_reach(spec, draw, var)
    clean = reach_positions(reach, clock)
    if still:
        clean = np.repeat(reach.points[:1], times.size, axis=0)
    human, modalities, extra = observe_human(observe, times, clean, tracker, draw.tracker_seed,
                                             arm_model)
    kin = kinematics()
    robot = joint_trajectory(clock, q_goal, draw.robot_on, draw.robot_off, draw.wobble,
                             (kin.lower, kin.upper))
    meet = max(draw.t_off, draw.robot_off)
    row = min(int(np.searchsorted(clock, meet - 1e-9)), times.size - 1)
    meta = {"hand_end": reach.end, "reach_time": (draw.t_on, draw.t_off),
            "robot_time": (draw.robot_on, draw.robot_off), "clean_human": clean,
            "handover_time": float(times[row]), **extra}
    return Demonstration(times=times, human=human, robot=robot, task=spec.name,
                         robot_names=ROBOT_NAMES, modalities=modalities, source="", meta=meta)


def _odd_specs(task_of: list[TaskSpec], specs: Sequence[TaskSpec], var: Variability,
               rng: np.random.Generator, ik_tol: float) -> list[TaskSpec]:
    """Per demonstration, its task veering to an odd endpoint (``"endpoint"``)."""
    ends = np.array([s.end + s.branch for s in specs])
    std = np.maximum(np.array(var.end_std), 1e-3)
    odd: list[TaskSpec | None] = [None] * len(task_of)
    for _ in range(50):
        todo = [i for i, o in enumerate(odd) if o is None]
        cand, owner = _odd_candidates([task_of[i] for i in todo], ends, std, rng)
        ok = solve_handover(cand + GRASP_OFFSET, ik_tol).success if len(cand) else []
        for end, j in zip(cand[ok], owner[ok], strict=True):
            spec = task_of[todo[j]]
            if odd[todo[j]] is None:
                odd[todo[j]] = TaskSpec("endpoint", end=spec.end, branch=end - spec.end,
                                        via=spec.via, duration=spec.duration)
        if all(o is not None for o in odd):
            return [o for o in odd if o is not None]
    raise ValueError("endpoint: found no reachable end outside every task (move the tasks)")


def _odd_candidates(task_of: list[TaskSpec], ends: FloatArray, std: FloatArray,
                    rng: np.random.Generator) -> tuple[FloatArray, np.ndarray]:
    """Candidate odd ends (m) around the demonstrations' tasks, those far from every task."""
    base_of = np.arange(len(task_of)).repeat(4)
    start = np.array([task_of[i].end + task_of[i].branch for i in base_of])
    direction = rng.normal(size=start.shape)
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    cand = start + direction * rng.uniform(MARGIN_M, MARGIN_M + 0.12, (len(start), 1))
    gap = cand[:, None, :] - ends[None]
    far = (np.linalg.norm(gap, axis=2).min(axis=1) >= MARGIN_M) & \
        (np.linalg.norm(gap / std, axis=2).min(axis=1) >= MARGIN_STD)
    return cand[far], base_of[far]
