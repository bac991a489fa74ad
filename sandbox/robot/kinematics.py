"""Forward kinematics of any arm of the registry, batched, in pure numpy.

:class:`ArmKinematics` serves every arm of :mod:`sandbox.robot.arms` (Baxter's
left arm, the Panda, the UR5, the Kinova); :class:`BaxterKinematics` is
Baxter's. The URDF joint chain from the arm's root frame to a link is folded into
fixed transforms ``F_j`` and joint rotations,

.. math::

    T(q) = F_0 \\, R(a_0, q_0) \\, F_1 \\, R(a_1, q_1) \\cdots R(a_{n-1}, q_{n-1}) \\, F_n,

evaluated for any leading batch shape of ``q``. The position Jacobian column of
revolute joint ``i`` is ``z_i x (p - o_i)`` and the angular one ``z_i``, with
``o_i`` and ``z_i`` the joint's origin and axis in the base frame.

Frames (names from the URDF): ``left_hand_link`` is the wrist flange, the
frame the recordings call ``baxter_left_hand``; ``left_gripper`` is the
electric gripper's fingertip point, 0.1577 m further along the flange's z.
Positions are in the arm's root frame (Baxter's ``base``; for the others the URDF's
root link, placed in the world at :attr:`~sandbox.robot.arms.ArmSpec.base`), in
metres; angles in radians.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sandbox.robot import ik as _ik
from sandbox.robot.arm_files import arm_urdf_path
from sandbox.robot.arms import ArmSpec, arm_spec
from sandbox.robot.assets import source_urdf_path
from sandbox.robot.facts import ARM_JOINTS, Q_HOME
from sandbox.robot.urdf import UrdfJoint, chain_to, read_joints
from sandbox.validation import check_array

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class _Chain:
    """A link's kinematic chain: ``T = F_0 R(a_0, q[i_0]) F_1 ... R(a_k, q[i_k]) F_k+1``."""

    fixed: tuple[FloatArray, ...]  # k + 1 transforms (4, 4)
    axes: tuple[FloatArray, ...]  # k unit axes (3,), in the joint frame
    index: tuple[int, ...]  # k indices into q


def _fold(chain: list[UrdfJoint], arm: tuple[str, ...]) -> _Chain:
    fixed, axes, index = [], [], []
    current = np.eye(4)
    for joint in chain:
        current = current @ joint.origin
        if joint.type == "fixed":
            continue
        if joint.name not in arm or joint.type not in ("revolute", "continuous"):
            raise ValueError(
                f"link: expected a link moved only by the arm's joints {arm}, "
                f"got one below {joint.type} joint {joint.name!r}"
            )
        fixed.append(current)
        axes.append(joint.axis)
        index.append(arm.index(joint.name))
        current = np.eye(4)
    fixed.append(current)
    return _Chain(tuple(fixed), tuple(axes), tuple(index))


@dataclass(frozen=True)
class _Model:
    chains: dict[str, _Chain]
    lower: FloatArray
    upper: FloatArray
    velocity: FloatArray


@functools.cache
def _load_model(path: str, arm: tuple[str, ...] = ARM_JOINTS) -> _Model:
    joints = read_joints(path)
    chains = {}
    for link in joints:
        try:
            chains[link] = _fold(chain_to(joints, link), arm)
        except ValueError:
            continue  # moved by a joint outside the arm (head, other arm, fingers)
    root = chain_to(joints, next(iter(joints)))[0].parent
    chains[root] = _Chain((np.eye(4),), (), ())
    by_name = {j.name: j for j in joints.values()}
    missing = [n for n in arm if n not in by_name]
    if missing:
        what = "Baxter's left-arm" if arm == ARM_JOINTS else "the arm's"
        raise ValueError(f"{path}: expected {what} joints, missing {missing}")
    lower = np.array([by_name[n].lower for n in arm])
    upper = np.array([by_name[n].upper for n in arm])
    velocity = np.array([by_name[n].velocity for n in arm])
    return _Model(chains, _readonly(lower), _readonly(upper), _readonly(velocity))


def _readonly(x: FloatArray) -> FloatArray:
    x = np.array(x, dtype=np.float64)
    x.flags.writeable = False
    return x


def _rotation(axis: FloatArray, angle: FloatArray) -> FloatArray:
    """Homogeneous rotations (..., 4, 4) about a unit ``axis`` by ``angle`` (...) rad."""
    c, s = np.cos(angle), np.sin(angle)
    out = np.zeros(angle.shape + (4, 4))
    out[..., 3, 3] = 1.0
    if axis[2] == 1.0:  # z, as for all of Baxter's arm joints: fast path
        out[..., 0, 0], out[..., 0, 1], out[..., 1, 0], out[..., 1, 1] = c, -s, s, c
        out[..., 2, 2] = 1.0
        return out
    x, y, z = axis
    k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    out[..., :3, :3] = (
        np.eye(3) + s[..., None, None] * k + (1.0 - c)[..., None, None] * (k @ k)
    )  # Rodrigues
    return out


class ArmKinematics:
    """Forward and inverse kinematics of one arm of the registry (pure numpy).

    Parsing the URDF is done once per process, URDF path and arm, so
    constructing this object again is cheap.

    Parameters
    ----------
    robot : str
        A name of :data:`sandbox.robot.arms.ROBOTS` (default ``"baxter"``).
    urdf : str or pathlib.Path, optional
        The robot's URDF; default the one of the installed ``example-robot-data``
        (with the sandbox's gripper changes, :func:`sandbox.robot.arm_files.arm_text`).

    Attributes
    ----------
    spec : ArmSpec
        The robot's description.
    joint_names : tuple of str
        The arm joints, the order of ``q``; ``dof`` of them.
    lower, upper : ndarray, shape (dof,)
        Joint limits (rad), read-only.
    max_velocity : ndarray, shape (dof,)
        Joint speed limits (rad/s), the URDF's ``<limit velocity>``, read-only.
    links : tuple of str
        Links whose pose depends only on ``q`` (arm, gripper and fixed body links).
    tip_link : str
        The link placed at the handover point.

    Examples
    --------
    >>> import numpy as np
    >>> kin = ArmKinematics("ur5")
    >>> kin.dof, kin.fk(np.zeros((4, 6))).shape
    (6, (4, 3))
    """

    #: Link of :meth:`fk` when none is given (Baxter: the wrist flange, as ever).
    default_link: str | None = None

    def __init__(self, robot: str = "baxter", urdf: str | Path | None = None) -> None:
        self.spec: ArmSpec = arm_spec(robot)
        if urdf is None:
            urdf = source_urdf_path() if robot == "baxter" else arm_urdf_path(robot)
        self.joint_names = self.spec.joints
        self.dof = len(self.joint_names)
        self.tip_link = self.spec.tip_link
        self._model = _load_model(str(Path(urdf).resolve()), self.joint_names)
        self.lower = self._model.lower
        self.upper = self._model.upper
        self.max_velocity = self._model.velocity
        self.links = tuple(sorted(self._model.chains))

    # -- forward kinematics ------------------------------------------------------------------

    def fk(self, q: ArrayLike, link: str | None = None) -> FloatArray:
        """Position of ``link`` (..., 3) in the root frame (m) for joints ``q`` (..., dof) rad
        (default link: :attr:`default_link`, else the tip)."""
        return self.fk_pose(q, link or self.default_link or self.tip_link)[..., :3, 3]

    def fk_pose(self, q: ArrayLike, link: str | None = None) -> FloatArray:
        """Pose (..., 4, 4) of ``link`` (default the tip) in the root frame (m) for ``q``
        (..., dof) rad."""
        q = self._check_q(q)
        return _forward(q, self._chain(link or self.tip_link))[0]

    def link_poses(
        self, q: ArrayLike, links: tuple[str, ...] | None = None
    ) -> dict[str, FloatArray]:
        """Poses (..., 4, 4) of several links (default: all of :attr:`links`), keyed by name."""
        q = self._check_q(q)
        chains = {name: self._chain(name) for name in (self.links if links is None else links)}
        return {name: _forward(q, chain)[0] for name, chain in chains.items()}

    def jacobian(self, q: ArrayLike, link: str | None = None) -> FloatArray:
        """Geometric Jacobian (..., 6, dof) of ``link`` (default the tip): linear (m/rad)
        rows, then angular rows."""
        q = self._check_q(q)
        return _forward(q, self._chain(link or self.tip_link), jacobian=True)[1]

    # -- inverse kinematics ------------------------------------------------------------------

    def ik(
        self,
        targets: ArrayLike,
        q_seed: ArrayLike | None = None,
        link: str | None = None,
        tol: float = 0.01,
        **options,
    ) -> _ik.IKResult:
        """Joint configurations that place ``link`` at ``targets`` (damped least squares).

        Parameters
        ----------
        targets : array_like, shape (n, 3) or (3,)
            Target positions in the root frame (m).
        q_seed : array_like, shape (dof,) or (n, dof), optional
            Starting configuration(s) (rad), clipped to the limits; default the
            home configuration (Baxter's :data:`~sandbox.robot.Q_HOME`). Solutions stay near it.
        link : str, optional
            Link to place (default the tip: Baxter's :data:`~sandbox.robot.TIP_LINK`, the
            gripper's fingertip point).
        tol : float
            Success threshold on the position error (m).
        **options
            ``orientations`` (n, 3, 3) target rotations and ``angle_tol`` (rad),
            ``max_iter``, ``restarts``, ``damping``, ... : see
            :func:`sandbox.robot.ik.solve`.

        Returns
        -------
        IKResult
            ``q`` (n, dof) within limits, ``error`` (n,) m, ``success`` (n,) bool.
        """
        chain = self._chain(link or self.tip_link)
        if q_seed is None:
            q_seed = np.array(self.spec.q_home)
        return _ik.solve(
            lambda q, jac: _forward(q, chain, jacobian=jac),
            targets,
            q_seed,
            self.lower,
            self.upper,
            tol=tol,
            **options,
        )

    # -- internals ---------------------------------------------------------------------------

    def _chain(self, link: str) -> _Chain:
        if not isinstance(link, str) or link not in self._model.chains:
            raise ValueError(
                f"link: expected one of the links moved by the arm (e.g. "
                f"{self.default_link or self.tip_link!r}, {self.tip_link!r}; see "
                f"{type(self).__name__}().links), got {link!r}"
            )
        return self._model.chains[link]

    def _check_q(self, q: ArrayLike) -> FloatArray:
        arr = np.asarray(q)
        if arr.ndim == 0 or arr.shape[-1] != self.dof:
            raise ValueError(
                f"q: expected joint angles of shape (..., {self.dof}) rad, got shape {arr.shape}"
            )
        return check_array(arr, "q", arr.ndim)


class BaxterKinematics(ArmKinematics):
    """Forward and inverse kinematics of Baxter's left arm (pure numpy).

    :class:`ArmKinematics` of ``"baxter"``: :meth:`fk` defaults to the wrist flange
    ``left_hand_link``, the other methods to the fingertip :data:`~sandbox.robot.TIP_LINK`.

    Parameters
    ----------
    urdf : str or pathlib.Path, optional
        A Baxter URDF; default: the one of the installed ``example-robot-data``.

    Attributes
    ----------
    joint_names : tuple of str
        ``('left_s0', ..., 'left_w2')``, the order of ``q``.
    lower, upper : ndarray, shape (7,)
        Joint limits (rad), read-only.
    links : tuple of str
        Links whose pose depends only on ``q`` (arm, gripper and fixed body links).

    Examples
    --------
    >>> import numpy as np
    >>> kin = BaxterKinematics()
    >>> q = np.zeros((5, 7))
    >>> kin.fk(q).shape, kin.fk_pose(q[0], link="left_gripper").shape
    ((5, 3), (4, 4))
    """

    joint_names = ARM_JOINTS
    default_link = "left_hand_link"

    def __init__(self, urdf: str | Path | None = None) -> None:
        super().__init__("baxter", urdf)


def _cross(a: FloatArray, b: FloatArray) -> FloatArray:
    """Cross products of (..., 3) arrays (faster than ``np.cross`` on small batches)."""
    return a[..., [1, 2, 0]] * b[..., [2, 0, 1]] - a[..., [2, 0, 1]] * b[..., [1, 2, 0]]


def _forward(
    q: FloatArray, chain: _Chain, jacobian: bool = False
) -> tuple[FloatArray, FloatArray | None]:
    """Pose (..., 4, 4) and, if asked, Jacobian (..., 6, dof) of a chain at ``q`` (..., dof)."""
    pose = np.broadcast_to(chain.fixed[0], q.shape[:-1] + (4, 4))
    origins, axes = [], []
    for fixed_next, axis, i in zip(chain.fixed[1:], chain.axes, chain.index, strict=True):
        if jacobian:
            origins.append(pose[..., :3, 3])
            axes.append(pose[..., :3, :3] @ axis)
        pose = pose @ _rotation(axis, q[..., i]) @ fixed_next
    if not jacobian:
        return np.array(pose), None
    jac = np.zeros(q.shape[:-1] + (6, q.shape[-1]))
    if chain.index:
        z, o = np.stack(axes, axis=-1), np.stack(origins, axis=-1)  # (..., 3, k)
        index = list(chain.index)
        jac[..., :3, index] = _cross(
            np.swapaxes(z, -1, -2), pose[..., None, :3, 3] - np.swapaxes(o, -1, -2)
        ).swapaxes(-1, -2)
        jac[..., 3:, index] = z
    return pose, jac


def q_home() -> FloatArray:
    """Baxter's left-arm home configuration (7,) rad: a writable copy of :data:`Q_HOME`."""
    return np.array(Q_HOME, dtype=np.float64)
