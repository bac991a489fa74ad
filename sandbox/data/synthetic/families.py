"""Task families: handing over objects at different places, and diverging motions.

``objects`` (the paper's Experiment 1)
    A box, a glasses case and a roll of tape handed over at different places
    and heights, each with one (unimodal) path. Spreads and timing are the
    ones measured on the recorded handovers, so its statistics resemble them
    (see :mod:`sandbox.data.synthetic.realism`).
``diverging`` (Experiment 2)
    Tasks that share their path until the divergence phase (0.5 +/- 0.05 of
    the demonstration), then turn left (+y), right (-y), up (+z), down (-z) or
    go straight on; their end points are ``branch_m`` (default 0.18 m) from the
    straight one, hence >= 15 cm apart from each other. The reach fills ~85 %
    of the demonstration and its primary submovement ~75 %, so the hand is
    still moving fast at the divergence.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from sandbox.data.demonstration import Demonstration
from sandbox.data.synthetic.arm import ArmModel
from sandbox.data.synthetic.generator import generate
from sandbox.data.synthetic.session import Session
from sandbox.data.synthetic.tasks import TaskSpec, Variability
from sandbox.data.synthetic.tracker import TrackerModel
from sandbox.validation import check_positive

#: The objects of Experiment 1: where (m) the hand ends on average, and how long (s) it takes.
OBJECTS = (
    TaskSpec("box", end=(0.81, 0.22, 0.17), duration=(2.05, 0.2)),
    TaskSpec("glasses_case", end=(0.80, 0.14, 0.30), duration=(2.4, 0.3)),
    TaskSpec("tape", end=(0.76, 0.27, 0.23), duration=(2.1, 0.3)),
)

#: Unit directions (Baxter's base frame) of the diverging tasks.
DIRECTIONS = {
    "left": (0.0, 1.0, 0.0),
    "right": (0.0, -1.0, 0.0),
    "up": (0.0, 0.0, 1.0),
    "down": (0.0, 0.0, -1.0),
    "straight": (0.0, 0.0, 0.0),
}
#: Mean end (m) of the shared (straight) path of the diverging tasks.
DIVERGING_END = np.array([0.80, 0.18, 0.22])
#: Variability of the diverging tasks: tight end points and via-points, a long
#: reach whose primary submovement is still under way at the divergence.
DIVERGING_VARIABILITY = Variability(
    end_std=(0.02, 0.02, 0.02), via_std=0.02, reach_on=(-0.03, 0.03), reach_off=(0.85, 0.03),
    primary=0.9, correction=(0.0, 0.1),
)


def diverging_specs(
    directions: Sequence[str] = tuple(DIRECTIONS), branch_m: float = 0.18
) -> tuple[TaskSpec, ...]:
    """Task specs of the diverging family (one per direction, named after it)."""
    branch_m = check_positive(branch_m, "branch_m")
    if isinstance(directions, str) or not directions or len(set(directions)) != len(directions):
        raise ValueError(f"directions: expected distinct names, got {directions!r}")
    for name in directions:
        if name not in DIRECTIONS:
            raise ValueError(f"directions: expected names from {list(DIRECTIONS)}, got {name!r}")
    return tuple(
        TaskSpec(name, end=DIVERGING_END, branch=branch_m * np.array(DIRECTIONS[name]),
                 duration=(2.4, 0.3))
        for name in directions
    )


def objects_demos(
    n_per_task: int,
    rng: np.random.Generator,
    *,
    tracker: TrackerModel | None = None,
    variability: Variability | None = None,
    rate_hz: float = 100.0,
    ik_tol: float = 0.01,
    observe: Sequence[str] | str = ("hand",),
    arm_model: ArmModel | None = None,
    session: Session | int | None = None,
) -> list[Demonstration]:
    """Handovers of a box, a glasses case and a roll of tape (Experiment 1).

    Parameters
    ----------
    n_per_task : int
        Demonstrations per object (>= 1).
    rng : numpy.random.Generator
        Source of randomness; the same seed gives the same demonstrations.
    tracker : TrackerModel, optional
        Tracker artefacts; default like the recordings, ``TrackerModel.clean()`` for none.
    variability : Variability, optional
        Spreads and timing; default measured on the recordings.
    rate_hz : float
        Row rate (Hz).
    ik_tol : float
        Required gripper position error (m) at the handover point.
    observe : str or sequence of str
        Observed modalities: ``"hand"`` (default), ``"hand,arm"`` (``human``
        has 9 columns, hand then elbow and shoulder) or ``"arm"``.
    arm_model : ArmModel, optional
        The human arm (default ``ArmModel()``), used when the arm is observed.
    session : Session or int, optional
        The recording session (see :func:`~sandbox.data.synthetic.generator.generate`);
        None: today's data.

    Returns
    -------
    list of Demonstration
        Tasks ``"box"``, ``"glasses_case"``, ``"tape"``, ``n_per_task`` each, in that order.
    """
    return generate(
        OBJECTS, n_per_task, rng, family="objects", tracker=tracker,
        variability=variability or Variability(), rate_hz=rate_hz, ik_tol=ik_tol,
        observe=observe, arm_model=arm_model, session=session,
    )


def diverging_demos(
    n_per_task: int,
    rng: np.random.Generator,
    *,
    directions: Sequence[str] = tuple(DIRECTIONS),
    branch_m: float = 0.18,
    tracker: TrackerModel | None = None,
    variability: Variability | None = None,
    rate_hz: float = 100.0,
    ik_tol: float = 0.01,
    observe: Sequence[str] | str = ("hand",),
    arm_model: ArmModel | None = None,
    session: Session | int | None = None,
) -> list[Demonstration]:
    """Tasks that share their start and diverge at phase ~0.5 (Experiment 2).

    Parameters
    ----------
    n_per_task : int
        Demonstrations per direction (>= 1).
    rng : numpy.random.Generator
        Source of randomness; the same seed gives the same demonstrations.
    directions : sequence of str
        Tasks, from ``"left", "right", "up", "down", "straight"``.
    branch_m : float
        Distance (m) of each branch's end from the straight path's end.
    tracker, variability, rate_hz, ik_tol, observe, arm_model, session
        As in :func:`objects_demos` (default variability:
        :data:`DIVERGING_VARIABILITY`).

    Returns
    -------
    list of Demonstration
        ``n_per_task`` demonstrations per direction, in the order of ``directions``;
        ``meta["divergence_time"]`` is when the branch starts (s).
    """
    return generate(
        diverging_specs(directions, branch_m), n_per_task, rng, family="diverging",
        tracker=tracker, variability=variability or DIVERGING_VARIABILITY, rate_hz=rate_hz,
        ik_tol=ik_tol, observe=observe, arm_model=arm_model, session=session,
    )
