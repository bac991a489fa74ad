"""Baxter in PyBullet: the only module of :mod:`sandbox.robot` that imports pybullet.

Every call goes through the ``BulletClient`` it is given, so several clients
(simulations) in one process never share state. Baxter is loaded from
:func:`sandbox.robot.urdf_path` with a fixed base at the world origin, so
PyBullet's world frame is Baxter's ``base`` frame.

Loading takes about 1.5 s (the DAE meshes); a second Baxter in the same client
reuses the parsed graphics shapes.
"""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sandbox.robot.arm_files import arm_urdf_path
from sandbox.robot.arms import arm_spec
from sandbox.robot.facts import ARM_JOINTS, TIP_LINK
from sandbox.robot.pybullet_quiet import BulletClient, pybullet
from sandbox.validation import check_array

FloatArray = NDArray[np.float64]
#: Left gripper finger joints (prismatic, m); the right one mirrors the left (URDF mimic).
FINGER_JOINTS = ("l_gripper_l_finger_joint", "l_gripper_r_finger_joint")


@dataclass(frozen=True)
class BulletBaxter:
    """A Baxter loaded in one PyBullet client.

    Attributes
    ----------
    client : BulletClient
        The client it lives in.
    body : int
        Body unique id in that client.
    joints : dict of str to int
        Joint name -> joint index (every joint, fixed ones included).
    links : dict of str to int
        Link name -> link index; the root link ``base`` is -1.
    arm : tuple of int
        Indices of the left-arm joints, in the order of :data:`ARM_JOINTS`.
    fingers : tuple of int
        Indices of :data:`FINGER_JOINTS`.
    limits : dict of str to (float, float)
        Lower and upper limit of every movable joint (rad or m).
    lower, upper : ndarray, shape (7,)
        Left-arm joint limits (rad).
    """

    client: BulletClient
    body: int
    joints: dict[str, int]
    links: dict[str, int]
    arm: tuple[int, ...]
    fingers: tuple[int, int]
    limits: dict[str, tuple[float, float]]
    lower: FloatArray
    upper: FloatArray


@contextlib.contextmanager
def _quiet() -> Iterator[None]:
    """Silence the C library's stdout (PyBullet's URDF warnings), best effort."""
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):
        yield
        return
    sys.stdout.flush()
    saved = os.dup(fd)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), fd)
            yield
    finally:
        os.dup2(saved, fd)
        os.close(saved)


def connect() -> BulletClient:
    """A new headless (DIRECT) PyBullet client, independent of any other in the process."""
    return BulletClient(connection_mode=pybullet.DIRECT)


def load_baxter(client: BulletClient, *, quiet: bool = True) -> BulletBaxter:
    """Load Baxter with a fixed base at the origin of ``client``'s world.

    Parameters
    ----------
    client : pybullet_utils.bullet_client.BulletClient
        A connected client (e.g. ``BulletClient(pybullet.DIRECT)``).
    quiet : bool
        Hide PyBullet's warnings about links without inertia while loading.

    Returns
    -------
    BulletBaxter
        The body id and name -> index maps; the arm is at zero.
    """
    return load_robot(client, "baxter", quiet=quiet)


def load_robot(client: BulletClient, robot: str = "baxter", *,
               quiet: bool = True) -> BulletBaxter:
    """Load any arm of :mod:`sandbox.robot.arms` with a fixed base at its world pose.

    Parameters
    ----------
    client : pybullet_utils.bullet_client.BulletClient
        A connected client.
    robot : str
        A name of :data:`sandbox.robot.arms.ROBOTS` (Baxter stands at the origin).
    quiet : bool
        Hide PyBullet's warnings while loading.

    Returns
    -------
    BulletBaxter
        The body id and name -> index maps of that arm (``arm``: its driven joints,
        ``fingers``: its two finger joints); the arm is at zero.
    """
    spec = arm_spec(robot)
    if not isinstance(client, BulletClient):
        raise ValueError(
            f"client: expected a pybullet_utils BulletClient, got {type(client).__name__}"
        )
    flags = pybullet.URDF_ENABLE_CACHED_GRAPHICS_SHAPES
    position = spec.base[:3, 3].tolist()
    orientation = _quaternion(spec.base[:3, :3])
    with _quiet() if quiet else contextlib.nullcontext():
        body = client.loadURDF(str(arm_urdf_path(robot)), position, orientation,
                               useFixedBase=True, flags=flags)
    joints, links, limits = {}, {client.getBodyInfo(body)[0].decode(): -1}, {}
    for index in range(client.getNumJoints(body)):
        info = client.getJointInfo(body, index)
        name = info[1].decode()
        joints[name] = index
        links[info[12].decode()] = index
        if info[2] != pybullet.JOINT_FIXED:
            limits[name] = (float(info[8]), float(info[9]))
    arm = tuple(joints[n] for n in spec.joints)
    return BulletBaxter(
        client=client,
        body=body,
        joints=joints,
        links=links,
        arm=arm,
        fingers=(joints[spec.fingers[0]], joints[spec.fingers[1]]),
        limits=limits,
        lower=np.array([limits[n][0] for n in spec.joints]),
        upper=np.array([limits[n][1] for n in spec.joints]),
    )


def _quaternion(rotation: FloatArray) -> list[float]:
    """Quaternion (x, y, z, w) of a rotation matrix (3, 3)."""
    from scipy.spatial.transform import Rotation

    return [float(v) for v in Rotation.from_matrix(rotation).as_quat()]


def reset_arm(baxter: BulletBaxter, q: ArrayLike) -> None:
    """Teleport the left arm to ``q`` (7,) rad (no dynamics; velocities zero)."""
    q = check_array(q, "q", 1, shape=(len(ARM_JOINTS),))
    for index, value in zip(baxter.arm, q, strict=True):
        baxter.client.resetJointState(baxter.body, index, float(value))


def arm_positions(baxter: BulletBaxter) -> FloatArray:
    """Current left-arm joint positions (7,) rad."""
    states = baxter.client.getJointStates(baxter.body, baxter.arm)
    return np.array([s[0] for s in states])


def reset_gripper(baxter: BulletBaxter, opening: float) -> None:
    """Teleport the left fingers to ``opening`` in [0, 1], mirrored.

    0 puts both fingers at their inner limit (closed), 1 at their outer limit:
    the fingertips are then 2 x 20.8 mm further apart.
    """
    if not np.isfinite(opening) or not 0.0 <= opening <= 1.0:
        raise ValueError(f"opening: expected a number in [0, 1], got {opening!r}")
    travel = baxter.limits[FINGER_JOINTS[0]][1] * float(opening)
    baxter.client.resetJointState(baxter.body, baxter.fingers[0], travel)
    baxter.client.resetJointState(baxter.body, baxter.fingers[1], -travel)


def link_pose(baxter: BulletBaxter, link: str) -> FloatArray:
    """Pose (4, 4) of ``link``'s URDF frame in the world (m), from PyBullet's link state."""
    if link not in baxter.links:
        raise ValueError(f"link: expected one of Baxter's links, got {link!r}")
    index = baxter.links[link]
    if index == -1:
        position, quaternion = baxter.client.getBasePositionAndOrientation(baxter.body)
    else:
        state = baxter.client.getLinkState(baxter.body, index, computeForwardKinematics=True)
        position, quaternion = state[4], state[5]
    pose = np.eye(4)
    pose[:3, :3] = np.reshape(baxter.client.getMatrixFromQuaternion(quaternion), (3, 3))
    pose[:3, 3] = position
    return pose


def bullet_ik(
    baxter: BulletBaxter,
    target: ArrayLike,
    q_seed: ArrayLike,
    *,
    link: str = TIP_LINK,
    tol: float = 0.01,
    max_rounds: int = 20,
) -> tuple[FloatArray, float]:
    """PyBullet's IK, iterated until the position error is at most ``tol``.

    One ``calculateInverseKinematics`` call misses by centimetres: this resets
    the arm to each solution (clipped to the limits, which are also passed to
    the solver) and solves again, up to ``max_rounds`` times. The arm's state
    is restored afterwards. Kept to cross-check and benchmark
    :meth:`sandbox.robot.BaxterKinematics.ik`, which is faster and batched.

    Parameters
    ----------
    baxter : BulletBaxter
        The loaded robot.
    target : array_like, shape (3,)
        Target position of ``link`` in the world frame (m).
    q_seed : array_like, shape (7,)
        Starting configuration (rad).
    link : str
        Link to place.
    tol : float
        Position tolerance (m).
    max_rounds : int
        Maximum number of solver calls.

    Returns
    -------
    q : ndarray, shape (7,)
        Best configuration found (rad), within limits.
    error : float
        Its position error (m).
    """
    target = check_array(target, "target", 1, shape=(3,))
    q = np.clip(
        check_array(q_seed, "q_seed", 1, shape=(len(ARM_JOINTS),)), baxter.lower, baxter.upper
    )
    if link not in baxter.links or baxter.links[link] < 0:
        raise ValueError(f"link: expected one of Baxter's moving links, got {link!r}")
    saved = arm_positions(baxter)
    best_q, best_err = q, np.inf
    try:
        for calls in range(int(max_rounds) + 1):
            reset_arm(baxter, q)
            err = float(np.linalg.norm(link_pose(baxter, link)[:3, 3] - target))
            if err < best_err:
                best_q, best_err = q, err
            if err <= tol or calls == max_rounds:
                break
            q = _bullet_ik_call(baxter, link, target)
    finally:
        reset_arm(baxter, saved)
    return best_q, best_err


def _bullet_ik_call(baxter: BulletBaxter, link: str, target: FloatArray) -> FloatArray:
    """One ``calculateInverseKinematics`` call from the current state: arm joints (7,) rad,
    clipped to the limits."""
    movable = sorted(baxter.joints[name] for name in baxter.limits)
    lows = [baxter.limits[n][0] for n in sorted(baxter.limits, key=baxter.joints.get)]
    highs = [baxter.limits[n][1] for n in sorted(baxter.limits, key=baxter.joints.get)]
    slot = [movable.index(i) for i in baxter.arm]
    rest = [s[0] for s in baxter.client.getJointStates(baxter.body, movable)]
    solution = baxter.client.calculateInverseKinematics(
        baxter.body,
        baxter.links[link],
        target.tolist(),
        lowerLimits=lows,
        upperLimits=highs,
        jointRanges=[h - lo for lo, h in zip(lows, highs, strict=True)],
        restPoses=rest,
        maxNumIterations=100,
        residualThreshold=1e-5,
    )
    return np.clip(np.array([solution[s] for s in slot]), baxter.lower, baxter.upper)
