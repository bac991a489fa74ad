"""Forward kinematics of Baxter's left arm, batched, in pure numpy.

The URDF joint chain from Baxter's ``base`` frame to a link is folded into
fixed transforms ``F_j`` and joint rotations,

.. math::

    T(q) = F_0 \\, R(a_0, q_0) \\, F_1 \\, R(a_1, q_1) \\cdots R(a_6, q_6) \\, F_7,

evaluated for any leading batch shape of ``q``. The position Jacobian column of
revolute joint ``i`` is ``z_i x (p - o_i)`` and the angular one ``z_i``, with
``o_i`` and ``z_i`` the joint's origin and axis in the base frame.

Frames (names from the URDF): ``left_hand_link`` is the wrist flange, the
frame the recordings call ``baxter_left_hand``; ``left_gripper`` is the
electric gripper's fingertip point, 0.1577 m further along the flange's z.
All positions are in Baxter's ``base`` frame, in metres; angles in radians.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sandbox.robot import ik as _ik
from sandbox.robot.assets import source_urdf_path
from sandbox.robot.facts import ARM_JOINTS, Q_HOME, TIP_LINK
from sandbox.robot.urdf import UrdfJoint, chain_to, read_joints
from sandbox.validation import check_array

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class _Chain:
    """A link's kinematic chain: ``T = F_0 R(a_0, q[i_0]) F_1 ... R(a_k, q[i_k]) F_k+1``."""

    fixed: tuple[FloatArray, ...]  # k + 1 transforms (4, 4)
    axes: tuple[FloatArray, ...]  # k unit axes (3,), in the joint frame
    index: tuple[int, ...]  # k indices into q


def _fold(chain: list[UrdfJoint]) -> _Chain:
    fixed, axes, index = [], [], []
    current = np.eye(4)
    for joint in chain:
        current = current @ joint.origin
        if joint.type == "fixed":
            continue
        if joint.name not in ARM_JOINTS or joint.type not in ("revolute", "continuous"):
            raise ValueError(
                f"link: expected a link moved only by the left arm's joints {ARM_JOINTS}, "
                f"got one below {joint.type} joint {joint.name!r}"
            )
        fixed.append(current)
        axes.append(joint.axis)
        index.append(ARM_JOINTS.index(joint.name))
        current = np.eye(4)
    fixed.append(current)
    return _Chain(tuple(fixed), tuple(axes), tuple(index))


@dataclass(frozen=True)
class _Model:
    chains: dict[str, _Chain]
    lower: FloatArray
    upper: FloatArray


@functools.cache
def _load_model(path: str) -> _Model:
    joints = read_joints(path)
    chains = {}
    for link in joints:
        try:
            chains[link] = _fold(chain_to(joints, link))
        except ValueError:
            continue  # moved by a joint outside the left arm (head, right arm, fingers)
    root = chain_to(joints, next(iter(joints)))[0].parent
    chains[root] = _Chain((np.eye(4),), (), ())
    by_name = {j.name: j for j in joints.values()}
    missing = [n for n in ARM_JOINTS if n not in by_name]
    if missing:
        raise ValueError(f"{path}: expected Baxter's left-arm joints, missing {missing}")
    lower = np.array([by_name[n].lower for n in ARM_JOINTS])
    upper = np.array([by_name[n].upper for n in ARM_JOINTS])
    return _Model(chains, _readonly(lower), _readonly(upper))


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


class BaxterKinematics:
    """Forward and inverse kinematics of Baxter's left arm (pure numpy).

    Parsing the URDF is done once per process and URDF path, so constructing
    this object again is cheap.

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

    def __init__(self, urdf: str | Path | None = None) -> None:
        path = Path(urdf) if urdf is not None else source_urdf_path()
        self._model = _load_model(str(path.resolve()))
        self.lower = self._model.lower
        self.upper = self._model.upper
        self.links = tuple(sorted(self._model.chains))

    # -- forward kinematics ------------------------------------------------------------------

    def fk(self, q: ArrayLike, link: str = "left_hand_link") -> FloatArray:
        """Position of ``link`` (..., 3) in the base frame (m) for joints ``q`` (..., 7) rad."""
        return self.fk_pose(q, link)[..., :3, 3]

    def fk_pose(self, q: ArrayLike, link: str = TIP_LINK) -> FloatArray:
        """Pose (..., 4, 4) of ``link`` in the base frame (m) for joints ``q`` (..., 7) rad."""
        q = self._check_q(q)
        return _forward(q, self._chain(link))[0]

    def link_poses(
        self, q: ArrayLike, links: tuple[str, ...] | None = None
    ) -> dict[str, FloatArray]:
        """Poses (..., 4, 4) of several links (default: all of :attr:`links`), keyed by name."""
        q = self._check_q(q)
        chains = {name: self._chain(name) for name in (self.links if links is None else links)}
        return {name: _forward(q, chain)[0] for name, chain in chains.items()}

    def jacobian(self, q: ArrayLike, link: str = TIP_LINK) -> FloatArray:
        """Geometric Jacobian (..., 6, 7) of ``link``: linear (m/rad) rows, then angular rows."""
        q = self._check_q(q)
        return _forward(q, self._chain(link), jacobian=True)[1]

    # -- inverse kinematics ------------------------------------------------------------------

    def ik(
        self,
        targets: ArrayLike,
        q_seed: ArrayLike | None = None,
        link: str = TIP_LINK,
        tol: float = 0.01,
        **options,
    ) -> _ik.IKResult:
        """Joint configurations that place ``link`` at ``targets`` (damped least squares).

        Parameters
        ----------
        targets : array_like, shape (n, 3) or (3,)
            Target positions in the base frame (m).
        q_seed : array_like, shape (7,) or (n, 7), optional
            Starting configuration(s) (rad), clipped to the limits; default the
            recorded home configuration :data:`~sandbox.robot.Q_HOME`. Solutions stay near it.
        link : str
            Link to place (default :data:`~sandbox.robot.TIP_LINK`, the gripper's fingertip
            point).
        tol : float
            Success threshold on the position error (m).
        **options
            ``orientations`` (n, 3, 3) target rotations and ``angle_tol`` (rad),
            ``max_iter``, ``restarts``, ``damping``, ... : see
            :func:`sandbox.robot.ik.solve`.

        Returns
        -------
        IKResult
            ``q`` (n, 7) within limits, ``error`` (n,) m, ``success`` (n,) bool.
        """
        chain = self._chain(link)
        if q_seed is None:
            q_seed = q_home()
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
                f"link: expected one of the links moved by the left arm (e.g. 'left_hand_link', "
                f"{TIP_LINK!r}; see BaxterKinematics().links), got {link!r}"
            )
        return self._model.chains[link]

    @staticmethod
    def _check_q(q: ArrayLike) -> FloatArray:
        arr = np.asarray(q)
        if arr.ndim == 0 or arr.shape[-1] != len(ARM_JOINTS):
            raise ValueError(
                f"q: expected joint angles of shape (..., 7) rad, got shape {arr.shape}"
            )
        return check_array(arr, "q", arr.ndim)


def _cross(a: FloatArray, b: FloatArray) -> FloatArray:
    """Cross products of (..., 3) arrays (faster than ``np.cross`` on small batches)."""
    return a[..., [1, 2, 0]] * b[..., [2, 0, 1]] - a[..., [2, 0, 1]] * b[..., [1, 2, 0]]


def _forward(
    q: FloatArray, chain: _Chain, jacobian: bool = False
) -> tuple[FloatArray, FloatArray | None]:
    """Pose (..., 4, 4) and, if asked, Jacobian (..., 6, 7) of a chain at ``q`` (..., 7)."""
    pose = np.broadcast_to(chain.fixed[0], q.shape[:-1] + (4, 4))
    origins, axes = [], []
    for fixed_next, axis, i in zip(chain.fixed[1:], chain.axes, chain.index, strict=True):
        if jacobian:
            origins.append(pose[..., :3, 3])
            axes.append(pose[..., :3, :3] @ axis)
        pose = pose @ _rotation(axis, q[..., i]) @ fixed_next
    if not jacobian:
        return np.array(pose), None
    jac = np.zeros(q.shape[:-1] + (6, len(ARM_JOINTS)))
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
