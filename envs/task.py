"""The handover task: the object in the human's hand, its transfer to the gripper, the reward.

While the human holds it, the object moves with the kinematic hand (teleported at
rest at every physics step; the hand body, which collides with nothing, at every
control step), its grasp point at
an offset from the tracked hand point: where the demonstrated gripper tip met
the hand, learned per task from the training demonstrations (the ``grasp_offset``
reset option, which the episode runners fill from the model's meeting geometry,
:mod:`sandbox.data.geometry`), else :data:`DEFAULT_HOLD_OFFSET`. When the gripper is
closed (:func:`~sandbox.envs.robot.RobotArm.gripper_closed`) with its
fingertip point within ``grasp_radius`` of the grasp point, the object is
fixed to the gripper where it is (a PyBullet constraint) and the hand lets go: that is the handover,
and the episode's success. The robot passes through the hand and the object
(their collisions are off), so reaching never pushes them.

Reward per step (:class:`RewardWeights`; the terms are returned in ``info``
and sum to the reward)::

    reward_distance    = -distance * d            d: fingertip to grasp point (m)
    reward_success     =  success  * [handover happened in this step]
    reward_action_rate = -action_rate * sum_j ((a_j - a_prev_j) / dt)^2   (rad/s)^2
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from sandbox import urdf
from sandbox.envs.human import HumanHand
from sandbox.envs.pybullet import Simulation, vec3
from sandbox.envs.robot import CLOSED_BELOW, RobotArm
from sandbox.robot import FLOOR_Z, GRASP_OFFSET
from sandbox.validation import check_positive

FloatArray = NDArray[np.float64]

#: Object for each task label (recorded tasks and the synthetic objects family).
TASK_OBJECTS = {
    "pencil_box": "box",
    "gummed_paper": "tape",
    "measurement_tape": "measuring_tape",
    "screw_driver": "screwdriver",
    "box": "box",
    "glasses_case": "glasses_case",
    "tape": "tape",
}
#: Object for any other task (e.g. the diverging family's).
DEFAULT_OBJECT = "box"
#: Grasp point of the held object relative to the tracked hand point (m) when an episode
#: gives none: the synthetic generator's default (:data:`sandbox.robot.GRASP_OFFSET`), right
#: for its sessionless synthetic motions. Recorded sessions differ from it by several cm:
#: give the model's learned geometry (``grasp_offset``) instead.
DEFAULT_HOLD_OFFSET = GRASP_OFFSET
#: Table placement (m): centre of its top surface, 0.74 m above the floor.
TABLE_TOP = np.array([0.85, 0.1, FLOOR_Z + 0.74])


@dataclass(frozen=True)
class RewardWeights:
    """Weights of the reward terms.

    Parameters
    ----------
    distance : float
        Per metre of fingertip-to-grasp-point distance, every step.
    success : float
        Bonus for the handover (once).
    action_rate : float
        Per (rad/s)^2 of the change of the joint targets between steps, summed over joints.
    """

    distance: float = 1.0
    success: float = 10.0
    action_rate: float = 0.01

    def __post_init__(self) -> None:
        for name in ("distance", "success", "action_rate"):
            check_positive(getattr(self, name), f"reward weight {name}", allow_zero=True)


def object_for(task: str, default: str = DEFAULT_OBJECT) -> str:
    """Object handed over in ``task`` (:data:`TASK_OBJECTS`, else ``default``)."""
    return TASK_OBJECTS.get(task, default)


class HandoverTask:
    """Objects, their transfer from the hand to the gripper, and the reward terms.

    Parameters
    ----------
    sim : Simulation
    robot : RobotArm
    human : HumanHand
    grasp_radius : float
        Largest fingertip-to-grasp-point distance (m) at which closing the gripper grasps.
    weights : RewardWeights
    """

    def __init__(self, sim: Simulation, robot: RobotArm, human: HumanHand, *,
                 grasp_radius: float = 0.05, weights: RewardWeights = RewardWeights()) -> None:
        self.sim, self.robot, self.human = sim, robot, human
        self.grasp_radius = check_positive(grasp_radius, "grasp_radius")
        self.weights = weights
        sim.load_urdf("floor", urdf.path("floor"), (0.0, 0.0, FLOOR_Z), fixed=True)
        sim.load_urdf("table", urdf.path("table"), TABLE_TOP, fixed=True)
        sim.disable_collisions(robot.name, human.name)
        for name in urdf.OBJECTS:
            sim.load_urdf(name, urdf.path(name), self.parking(name))
            sim.disable_collisions(robot.name, name)
            sim.disable_collisions(human.name, name)
        self.object: str | None = None
        self.hold_offset = np.array(DEFAULT_HOLD_OFFSET)
        self._constraint: int | None = None
        self.handed_over = False

    @staticmethod
    def parking(name: str) -> tuple[float, float, float]:
        """Where an unused object rests (m): on the floor behind Baxter."""
        return (-2.5, -1.0 + 0.5 * urdf.OBJECTS.index(name), FLOOR_Z + 0.06)

    def release(self) -> None:
        """Remove the object's constraint (call before restoring a saved state)."""
        if self._constraint is not None:
            self.sim.detach(self._constraint)
            self._constraint = None

    def reset(self, object_name: str, hand: FloatArray,
              hold_offset: FloatArray | None = None) -> None:
        """Put ``object_name`` in the hand at ``hand`` (3,) m, its grasp point at
        ``hold_offset`` (3,) m from it (default :data:`DEFAULT_HOLD_OFFSET`)."""
        if object_name not in urdf.OBJECTS:
            raise ValueError(f"object: expected one of {list(urdf.OBJECTS)}, got {object_name!r}")
        self.hold_offset = np.array(DEFAULT_HOLD_OFFSET if hold_offset is None else hold_offset,
                                    dtype=np.float64)
        self.release()
        self.object, self.handed_over = object_name, False
        self.move_hand(hand)

    def move_hand(self, hand: FloatArray) -> None:
        """Move the hand to ``hand`` (3,) m, and the object with it until the handover."""
        self.human.move_to(hand)
        if not self.handed_over:
            self.sim.set_pose(self._require_object(), hand + self.hold_offset, at_rest=True)

    def advance(self, hands: list[FloatArray]) -> None:
        """One physics step per hand position (3,) m of ``hands``, the hand and the object
        moved before each: what :meth:`move_hand` then a physics step does, for each.

        The hand body is kinematic and collides with nothing, so only its last pose shows:
        it is moved there once (the object, dynamic, at every step).
        """
        self.human.move_to(hands[-1])
        if self.handed_over:
            self.sim.advance(len(hands))
            return
        a, b, c = self.hold_offset.tolist()
        self.sim.advance(len(hands), self._require_object(),
                         [[x + a, y + b, z + c] for x, y, z in hands])

    def grasp_point(self) -> FloatArray:
        """World position (3,) m of the object's grasp point."""
        return np.array(self.grasp_floats())

    def grasp_floats(self) -> tuple[float, float, float]:
        """:meth:`grasp_point` as PyBullet gives it (3 floats, m)."""
        return self.sim.pose_floats(self._require_object())[0]

    def distance(self, grasp: FloatArray | Sequence[float] | None = None) -> float:
        """Fingertip-to-grasp-point distance (m); ``grasp`` (3,) m the grasp point if read
        already (:meth:`grasp_point` or :meth:`grasp_floats`)."""
        g0, g1, g2 = (self.grasp_floats() if grasp is None
                      else grasp if type(grasp) is tuple else vec3(grasp))
        t0, t1, t2 = self.sim.link_position_floats(self.robot.name, self.robot.tip_link)
        d0, d1, d2 = t0 - g0, t1 - g1, t2 - g2  # np.linalg.norm's value (checked), in floats
        return math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)

    def try_handover(self, opening: float | None = None, distance: float | None = None) -> bool:
        """Transfer the object if the closed gripper is within reach; True if it happened now.

        ``opening`` (:meth:`~sandbox.envs.robot.RobotArm.gripper_opening`) and ``distance``
        (:meth:`distance`, m) are read now if not given.
        """
        if opening is None:
            opening = self.robot.gripper_opening()
        if self.handed_over or not opening < CLOSED_BELOW:
            return False
        if (self.distance() if distance is None else distance) > self.grasp_radius:
            return False
        self.release()
        self._constraint = self.sim.attach(self.robot.name, self.robot.tip_link,
                                           self._require_object())
        self.handed_over = True
        return True

    def reward_terms(self, distance: float, handed_now: bool, rate: FloatArray) -> dict:
        """The reward terms (see the module docstring) from the step's outcome.

        Parameters
        ----------
        distance : float
            Fingertip-to-grasp-point distance (m) after the step.
        handed_now : bool
            Whether the handover happened in this step.
        rate : ndarray, shape (7,)
            Change of the joint targets divided by the control period (rad/s).
        """
        w = self.weights
        return {
            "reward_distance": -w.distance * distance,
            "reward_success": w.success if handed_now else 0.0,
            "reward_action_rate": -w.action_rate * float(np.dot(rate, rate)),
        }

    def _require_object(self) -> str:
        if self.object is None:
            raise RuntimeError("no object yet: reset the task first")
        return self.object
