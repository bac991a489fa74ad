"""The simulation: the only module of :mod:`sandbox.envs` that talks to PyBullet.

:class:`Simulation` owns one ``BulletClient`` in DIRECT mode (so several
environments in one process never share state) and names its bodies
(``"baxter"``, ``"table"``, ``"human_hand"``, objects...). The robot, the human
and the task reach the simulator only through it. A viewer can mirror the
scene from :attr:`Simulation.client` and :attr:`Simulation.bodies`.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sandbox.robot.bullet import BulletBaxter, _quiet, load_baxter, load_robot
from sandbox.robot.pybullet_quiet import BulletClient, pybullet
from sandbox.validation import check_positive

FloatArray = NDArray[np.float64]
IDENTITY = (0.0, 0.0, 0.0, 1.0)
_ZERO = [0.0, 0.0, 0.0]


class Simulation:
    """A headless PyBullet world with named bodies, stepped at a fixed rate.

    Parameters
    ----------
    physics_hz : float
        Physics rate (Hz); one :meth:`step_physics` advances ``1 / physics_hz`` s.
    gravity : float
        Gravity along z (m/s^2).

    Attributes
    ----------
    client : pybullet_utils.bullet_client.BulletClient
        The client (read-only use by viewers).
    bodies : dict of str to int
        Body name -> body unique id.
    time_step : float
        Physics time step (s).
    """

    def __init__(self, physics_hz: float = 250.0, gravity: float = -9.81) -> None:
        self.time_step = 1.0 / check_positive(physics_hz, "physics_hz")
        with _quiet():  # PyBullet prints 'argv[0]=' on connecting
            self.client = BulletClient(connection_mode=pybullet.DIRECT)
        # The calls made at every step go to pybullet with this id, not through the client
        # (its __getattr__ builds a partial per call: a tenth of a step's Python time);
        # ``_cid`` is passed by position, which PyBullet parses faster than a keyword.
        self._id = {"physicsClientId": self.client._client}
        self._cid: int = self.client._client
        self.client.setTimeStep(self.time_step)
        self.client.setGravity(0.0, 0.0, float(gravity))
        self.client.setPhysicsEngineParameter(deterministicOverlappingPairs=1)
        self.bodies: dict[str, int] = {}
        self._state: int | None = None
        self._closed = False

    # ------------------------------------------------------------------ bodies
    def load_baxter(self, name: str = "baxter") -> BulletBaxter:
        """Load Baxter (fixed base at the origin) as body ``name``."""
        baxter = load_baxter(self.client)
        self.bodies[name] = baxter.body
        return baxter

    def load_robot(self, name: str, robot: str = "baxter") -> BulletBaxter:
        """Load an arm of :mod:`sandbox.robot.arms` (fixed base at its world pose) as ``name``."""
        arm = load_robot(self.client, robot)
        self.bodies[name] = arm.body
        return arm

    def load_urdf(self, name: str, path: str | Path, position: ArrayLike,
                  orientation: Sequence[float] = IDENTITY, *, fixed: bool = False) -> int:
        """Load a URDF file as body ``name`` at ``position`` (3,) m, quaternion (x, y, z, w)."""
        if name in self.bodies:
            raise ValueError(f"name: a body called {name!r} exists already")
        body = self.client.loadURDF(str(path), vec3(position), list(orientation),
                                    useFixedBase=bool(fixed))
        self.bodies[name] = body
        return body

    def set_pose(self, name: str, position: ArrayLike,
                 orientation: Sequence[float] = IDENTITY, *, at_rest: bool = False) -> None:
        """Teleport body ``name``'s base to ``position`` (3,) m, ``orientation`` (4,).

        ``at_rest`` also zeroes its velocity (for a dynamic body moved kinematically).
        """
        body = self.bodies[name]
        pybullet.resetBasePositionAndOrientation(body, vec3(position), orientation, self._cid)
        if at_rest:
            pybullet.resetBaseVelocity(body, _ZERO, _ZERO, self._cid)

    def pose(self, name: str) -> tuple[FloatArray, FloatArray]:
        """Base position (3,) m and quaternion (4,) (x, y, z, w) of body ``name``."""
        position, quaternion = self.pose_floats(name)
        return np.array(position), np.array(quaternion)

    def pose_floats(self, name: str) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """:meth:`pose` as PyBullet gives it: position (3 floats, m), quaternion (4 floats)."""
        return pybullet.getBasePositionAndOrientation(self.bodies[name], self._cid)

    def link_position(self, name: str, link: int) -> FloatArray:
        """World position (3,) m of the URDF frame of ``link`` of body ``name``."""
        return np.array(self.link_position_floats(name, link))

    def link_position_floats(self, name: str, link: int) -> tuple[float, float, float]:
        """:meth:`link_position` as PyBullet gives it (3 floats, m)."""
        # positional: computeLinkVelocity 0, computeForwardKinematics 1
        return pybullet.getLinkState(self.bodies[name], link, 0, 1, self._cid)[4]

    def link_pose(self, name: str, link: int) -> tuple[FloatArray, FloatArray]:
        """World position (3,) and quaternion (4,) of the URDF frame of ``link``."""
        state = self.client.getLinkState(self.bodies[name], link, computeForwardKinematics=True)
        return np.array(state[4]), np.array(state[5])

    def disable_collisions(self, name_a: str, name_b: str) -> None:
        """Let bodies ``name_a`` and ``name_b`` pass through each other (every link pair)."""
        a, b = self.bodies[name_a], self.bodies[name_b]
        for link_a in range(-1, self.client.getNumJoints(a)):
            for link_b in range(-1, self.client.getNumJoints(b)):
                self.client.setCollisionFilterPair(a, b, link_a, link_b, 0)

    # ------------------------------------------------------------------ joints
    def joint_states(self, name: str, joints: Sequence[int]) -> tuple[FloatArray, FloatArray]:
        """Positions and velocities (n,) of ``joints`` of body ``name`` (rad or m, per s)."""
        positions, velocities = self.joint_states_floats(name, joints)
        return np.array(positions), np.array(velocities)

    def joint_states_floats(self, name: str, joints: Sequence[int]
                            ) -> tuple[list[float], list[float]]:
        """:meth:`joint_states` as Python floats: positions and velocities, lists of n."""
        states = pybullet.getJointStates(self.bodies[name], joints, self._cid)
        return [s[0] for s in states], [s[1] for s in states]

    def joint_limits(self, name: str, joints: Sequence[int]) -> tuple[FloatArray, FloatArray]:
        """Maximum effort (N m or N) and velocity (rad/s or m/s) of ``joints``, from the URDF."""
        infos = [self.client.getJointInfo(self.bodies[name], j) for j in joints]
        return np.array([i[10] for i in infos]), np.array([i[11] for i in infos])

    def reset_joints(self, name: str, joints: Sequence[int], positions: ArrayLike) -> None:
        """Teleport ``joints`` to ``positions`` with zero velocity."""
        for joint, value in zip(joints, np.asarray(positions, dtype=float), strict=True):
            self.client.resetJointState(self.bodies[name], joint, float(value))

    def control_joints(self, name: str, joints: Sequence[int], targets: ArrayLike,
                       forces: ArrayLike, max_velocities: ArrayLike) -> None:
        """Position-control ``joints`` toward ``targets`` with effort and speed limits.

        One PyBullet call per joint (``setJointMotorControl2``: the array call takes no speed
        limit). Each joint's motor keeps the speed limit until a command gives another, so
        later commands may go through :meth:`retarget_joints`.
        """
        body, control = self.bodies[name], pybullet.setJointMotorControl2
        for joint, target, force, speed in zip(joints, _floats(targets), _floats(forces),
                                               _floats(max_velocities), strict=True):
            control(body, joint, pybullet.POSITION_CONTROL, targetPosition=target,
                    force=force, maxVelocity=speed, **self._id)

    def retarget_joints(self, name: str, joints: list[int], targets: list[float],
                        forces: list[float]) -> None:
        """New position targets (and effort limits) for ``joints`` that :meth:`control_joints`
        commanded before: one PyBullet call (``setJointMotorControlArray``).

        The array call carries no speed limit; PyBullet's joint motor keeps the one the last
        :meth:`control_joints` gave (it changes its speed clamp only when a command carries
        one), so the motion is the same as with :meth:`control_joints`, bit for bit
        (``tests/envs/test_pybullet.py``). ``targets`` and ``forces``: lists of floats.
        """
        pybullet.setJointMotorControlArray(self.bodies[name], joints, pybullet.POSITION_CONTROL,
                                           targetPositions=targets, forces=forces,
                                           physicsClientId=self._cid)

    # ------------------------------------------------------------- constraints
    def attach(self, parent: str, parent_link: int, child: str, *,
               max_force: float = 200.0) -> int:
        """Fix body ``child`` to ``parent_link`` of ``parent`` where it is now; the id."""
        p_pos, p_orn = (self.pose(parent) if parent_link < 0
                        else self.link_pose(parent, parent_link))
        c_pos, c_orn = self.pose(child)
        inv_pos, inv_orn = self.client.invertTransform(p_pos.tolist(), p_orn.tolist())
        rel_pos, rel_orn = self.client.multiplyTransforms(inv_pos, inv_orn, c_pos.tolist(),
                                                          c_orn.tolist())
        cid = self.client.createConstraint(
            self.bodies[parent], parent_link, self.bodies[child], -1, pybullet.JOINT_FIXED,
            [0, 0, 0], rel_pos, [0, 0, 0], rel_orn, [0, 0, 0, 1])
        self.client.changeConstraint(cid, maxForce=float(max_force))
        return cid

    def detach(self, constraint: int) -> None:
        """Remove a constraint made by :meth:`attach`."""
        self.client.removeConstraint(constraint)

    # ---------------------------------------------------------------- stepping
    def step_physics(self) -> None:
        """Advance the world by one physics step."""
        pybullet.stepSimulation(self._cid)

    def advance(self, n: int, carried: str | None = None,
                positions: Sequence[Sequence[float]] = ()) -> None:
        """``n`` physics steps; before step k, body ``carried`` (if given) is put at
        ``positions[k]`` (3,) m, upright and at rest, as :meth:`set_pose` does.

        One call for a control step's substeps: their Python cost is a tenth of a step's.
        PyBullet's teleport (``resetBasePositionAndOrientation``) zeroes the base's velocity
        itself, so :meth:`set_pose`'s ``at_rest`` call is not needed here
        (``tests/envs/test_pybullet.py``).
        """
        step, cid = pybullet.stepSimulation, self._cid
        if carried is None:
            for _ in range(n):
                step(cid)
            return
        body, teleport = self.bodies[carried], pybullet.resetBasePositionAndOrientation
        if len(positions) != n:
            raise ValueError(f"positions: expected {n} (one per step), got {len(positions)}")
        for position in positions:
            teleport(body, vec3(position), IDENTITY, cid)
            step(cid)

    def save(self) -> None:
        """Remember the current state (in memory) for :meth:`restore`."""
        if self._state is not None:
            self.client.removeState(self._state)
        self._state = self.client.saveState()

    def restore(self) -> None:
        """Go back to the state of the last :meth:`save` (bodies are not reloaded)."""
        if self._state is None:
            raise RuntimeError("restore: nothing saved yet, call save() first")
        self.client.restoreState(self._state)

    # --------------------------------------------------------------- rendering
    def render(self, width: int = 480, height: int = 360, *, target: ArrayLike = (0.75, 0.1, 0.05),
               distance: float = 2.0, yaw: float = 50.0, pitch: float = -25.0,
               fov: float = 50.0) -> NDArray[np.uint8]:
        """RGB image (height, width, 3) from an orbit camera (TinyRenderer, no display).

        Parameters
        ----------
        width, height : int
            Image size (pixels).
        target : array_like, shape (3,)
            Point looked at (m).
        distance : float
            Camera distance from ``target`` (m).
        yaw, pitch : float
            Camera orbit angles (degrees).
        fov : float
            Vertical field of view (degrees).
        """
        view = self.client.computeViewMatrixFromYawPitchRoll(vec3(target), distance, yaw, pitch,
                                                             0.0, 2)
        proj = self.client.computeProjectionMatrixFOV(fov, width / height, 0.05, 20.0)
        _, _, rgba, _, _ = self.client.getCameraImage(
            int(width), int(height), view, proj, renderer=pybullet.ER_TINY_RENDERER)
        return np.reshape(np.asarray(rgba, dtype=np.uint8), (int(height), int(width), 4))[..., :3]

    def close(self) -> None:
        """Disconnect the client; calling it again does nothing."""
        if not self._closed:
            self._closed = True
            self.client.disconnect()


def _floats(x: ArrayLike) -> list[float]:
    """``x`` flattened to Python floats; a list is passed as it is (the per-step calls give
    lists of floats, PyBullet reads any number)."""
    if type(x) is list:
        return x
    return np.asarray(x, dtype=float).reshape(-1).tolist()


def vec3(x: ArrayLike) -> list[float]:
    """``x`` as three Python floats (a list of three floats as it is: see :func:`_floats`)."""
    if type(x) is list and len(x) == 3 and type(x[0]) is type(x[1]) is type(x[2]) is float:
        return x
    return np.asarray(x, dtype=float).reshape(3).tolist()
