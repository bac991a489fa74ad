"""Meeting geometry: where the robot's fingertip met the tracked hand, learned from the demos.

Where a handover happens relative to the *tracked* hand belongs to a recording
session, not to the method: it depends on the tracker's calibration (its frame
offset and rotation), on how the person holds the object and on where the robot
takes it. On recordings of one lab it moved by 7-8 cm from one session to
another, against a 5 cm grasp radius. So it is learned from the training
demonstrations, stored in the model file, and the environments place the
object's grasp point from it.

**The meeting moment** of a demonstration is the sample at which the robot's
fingertip (forward kinematics of the joints at :data:`~sandbox.robot.TIP_LINK`)
is nearest the object, which rides at the task's mean offset from the tracked
hand (its ``hand`` modality, NaN rows skipped): the robot took the object there,
and the hand retracts, lingers or is occluded after. The **offset** is fingertip
minus hand at that sample (m, Baxter's base frame). The mean and the moments
depend on each other; :func:`task_offsets` finds both by fixed-point iteration,
starting from the offsets when both partners have arrived (the motion's end of
:func:`sandbox.core.fitting.motion_end`). On the recorded set that
iteration puts the object within 4.5 cm of the recorded fingertip's path in
0.75 of the trials (leave-one-out), against 0.62 for a constant offset.
Per task, :class:`TaskGeometry` keeps the mean offset, its covariance and the
count of demonstrations.

Only demonstrations whose robot part is Baxter's seven left-arm joints
(:data:`~sandbox.robot.ARM_JOINTS`), or a task-space position x, y, z (m; the
fingertip is then that position, no kinematics), and that do not say
``meta["robot_meets_hand"] = False`` (the ``two_task`` generator's robot is a
fixed function of the hand, not a reach to it) carry a geometry. Data with none
keeps :data:`DEFAULT_OFFSET`, and says so (:func:`geometry_of`).

The model file keeps the geometry as the ``meeting_geometry`` entry of the
model's ``session`` metadata (:attr:`sandbox.core.IProMP.session`), which the
core stores but does not interpret.

Examples
--------
>>> import numpy as np
>>> from sandbox.core import IProMP
>>> from sandbox.data.synthetic import make_dataset
>>> demos = make_dataset("diverging", 4, np.random.default_rng(0))
>>> model = attach_geometry(IProMP(n_basis=15).fit(demos), demos)
>>> geometry, note = geometry_of(model)
>>> geometry.source, note
('learned', None)
>>> bool(np.linalg.norm(geometry.offset("left") - DEFAULT_OFFSET) < 0.05)
True
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from sandbox.robot import ARM_JOINTS, GRASP_OFFSET, TIP_LINK
from sandbox.validation import FloatArray, check_array

#: Key of the geometry in a model's ``session`` metadata.
GEOMETRY_KEY = "meeting_geometry"
#: Largest hand-to-fingertip offset (m) a demonstration may have at its meeting; more is
#: a unit or frame error (millimetres, another frame), not a handover.
MAX_OFFSET_M = 0.3
#: Offset (3,) m of the fingertip from the tracked hand for data that carries no geometry
#: (no Baxter robot part, or a model file older than the geometry): the synthetic
#: generator's default, :data:`sandbox.robot.GRASP_OFFSET`.
DEFAULT_OFFSET = GRASP_OFFSET
#: Both partners have arrived once the robot stays within ``SETTLE_TOL`` (rad) of its final
#: pose and the hand has come within ``ARRIVE_TOL`` (m) of its farthest reach: the models'
#: own defaults (:class:`sandbox.core.IProMP`, :func:`sandbox.core.fitting.motion_end`); a
#: task-space part (m) within ``SETTLE_TOL_M`` (5 cm would stop a receiving hand mid-approach).
SETTLE_TOL, ARRIVE_TOL, SETTLE_TOL_M = 0.05, 0.02, 0.005
#: Rounds of the fixed-point search for the meeting moments (:func:`task_offsets`).
MAX_ROUNDS = 20


@dataclass(frozen=True)
class TaskGeometry:
    """One task's hand-to-fingertip offset at the meeting.

    Attributes
    ----------
    mean : ndarray, shape (3,)
        Mean offset (m).
    cov : ndarray, shape (3, 3)
        Its covariance over the demonstrations (m^2; zeros for one demonstration).
    count : int
        Demonstrations it was learned from (0: the default).
    """

    mean: FloatArray
    cov: FloatArray
    count: int

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form."""
        return {"mean": self.mean.tolist(), "cov": self.cov.tolist(), "count": self.count}

    @classmethod
    def from_dict(cls, entry: Any, name: str) -> TaskGeometry:
        """Read :meth:`to_dict`'s form back, checked (``ValueError`` naming ``name``)."""
        if not isinstance(entry, Mapping) or set(entry) != {"mean", "cov", "count"}:
            raise ValueError(f"{name}: expected keys ['count', 'cov', 'mean'], got {entry!r:.80}")
        mean = check_array(entry["mean"], f"{name}.mean", 1, shape=(3,))
        cov = check_array(entry["cov"], f"{name}.cov", 2, shape=(3, 3))
        count = entry["count"]
        if isinstance(count, bool) or not isinstance(count, int) or count < 0:
            raise ValueError(f"{name}.count: expected an integer >= 0, got {count!r}")
        if np.linalg.norm(mean) > MAX_OFFSET_M:
            raise ValueError(f"{name}.mean: expected an offset within {MAX_OFFSET_M} m, got "
                             f"{np.linalg.norm(mean):.3f} m")
        if not np.allclose(cov, cov.T) or np.linalg.eigvalsh(cov).min() < -1e-12:
            raise ValueError(f"{name}.cov: expected a symmetric positive semi-definite matrix")
        return cls(mean, cov, count)


@dataclass(frozen=True)
class MeetingGeometry:
    """Per-task hand-to-fingertip offsets at the meeting (Baxter's base frame, m).

    Attributes
    ----------
    tasks : mapping of str to TaskGeometry
    source : {"learned", "default"}
        Learned from demonstrations, or :data:`DEFAULT_OFFSET` for every task.
    """

    tasks: Mapping[str, TaskGeometry] = field(default_factory=dict)
    source: str = "learned"

    def offset(self, task: str) -> FloatArray:
        """Mean offset (3,) m of ``task``; :data:`DEFAULT_OFFSET` for a default geometry.

        Raises
        ------
        ValueError
            If a learned geometry has no such task.
        """
        if self.source == "default":
            return np.array(DEFAULT_OFFSET)
        if task not in self.tasks:
            raise ValueError(f"task: expected one of {sorted(self.tasks)} (tasks with a "
                             f"learned meeting geometry), got {task!r}")
        return np.array(self.tasks[task].mean)

    def pooled(self) -> FloatArray:
        """Mean offset (3,) m over every task's demonstrations (the default's for a default
        geometry): for a hand motion of none of the tasks, e.g. a scripted one."""
        if self.source == "default" or not self.tasks:
            return np.array(DEFAULT_OFFSET)
        counts = np.array([max(g.count, 1) for g in self.tasks.values()], dtype=np.float64)
        means = np.array([g.mean for g in self.tasks.values()])
        return counts @ means / counts.sum()

    def offsets(self) -> dict[str, list[float]]:
        """Task -> mean offset (m), e.g. for an environment's ``grasp_offset`` reset option."""
        return {task: g.mean.tolist() for task, g in self.tasks.items()}

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form (the model file's ``meeting_geometry`` entry)."""
        return {"tasks": {k: g.to_dict() for k, g in self.tasks.items()}}

    @classmethod
    def from_dict(cls, entry: Any) -> MeetingGeometry:
        """Read :meth:`to_dict`'s form back, checked (``ValueError``)."""
        tasks = entry.get("tasks") if isinstance(entry, Mapping) else None
        if not isinstance(tasks, Mapping) or not tasks:
            raise ValueError(f"{GEOMETRY_KEY}: expected {{'tasks': {{name: ...}}}}, "
                             f"got {entry!r:.80}")
        return cls({str(k): TaskGeometry.from_dict(v, f"{GEOMETRY_KEY}[{k!r}]")
                    for k, v in tasks.items()})

    @classmethod
    def default(cls, tasks: Sequence[str] = ()) -> MeetingGeometry:
        """:data:`DEFAULT_OFFSET` for every task."""
        zero = np.zeros((3, 3))
        return cls({t: TaskGeometry(np.array(DEFAULT_OFFSET), zero, 0) for t in tasks},
                   "default")


def carries_geometry(demo) -> bool:
    """Whether ``demo``'s robot part is Baxter's left arm reaching to the hand, or a
    task-space position (x, y, z, m) that does (the receiving hand's, say)."""
    meta = getattr(demo, "meta", None) or {}
    if getattr(demo, "robot_space", "joint") == "task":
        arm = np.shape(demo.robot)[1] == 3
    else:
        arm = tuple(getattr(demo, "robot_names", ()) or ()) == ARM_JOINTS
    return arm and meta.get("robot_meets_hand", True) is not False


def _tip(demo, kinematics) -> FloatArray:
    """The robot's fingertip (T, 3) m over a demo: forward kinematics of its joints at
    :data:`~sandbox.robot.TIP_LINK`, or its task-space robot part as it is."""
    if getattr(demo, "robot_space", "joint") == "task":
        return np.asarray(demo.robot, dtype=np.float64)
    return kinematics.fk(demo.robot, link=TIP_LINK)


def meeting_offset(times, hand, robot, kinematics=None,
                   expected=None) -> tuple[FloatArray, int]:
    """Hand-to-fingertip offset of one demonstration at its meeting moment.

    Parameters
    ----------
    times : array_like, shape (T,)
        Sample times (s); only their count is used.
    hand : array_like, shape (T, 3)
        Tracked hand (m), NaN where missing.
    robot : array_like, shape (T, 7)
        Baxter's left-arm joints (rad).
    kinematics : BaxterKinematics, optional
        Reused if given.
    expected : array_like, shape (3,), optional
        Where the object is expected relative to the hand (m); the meeting is the
        sample where the fingertip is nearest ``hand + expected``. Default zeros:
        nearest the hand itself.

    Returns
    -------
    offset : ndarray, shape (3,)
        Fingertip minus hand (m) at the meeting moment.
    index : int
        The meeting sample.

    Raises
    ------
    ValueError
        If no sample has a finite hand.
    """
    from sandbox.robot import BaxterKinematics

    n = np.asarray(times).shape[0]
    hand = check_array(hand, "hand", 2, shape=(n, 3), allow_nan=True)
    robot = check_array(robot, "robot", 2, shape=(n, 7))
    shift = np.zeros(3) if expected is None else check_array(expected, "expected", 1, shape=(3,))
    tip = (kinematics or BaxterKinematics()).fk(robot, link=TIP_LINK)
    index = _nearest(hand, tip, shift)
    return tip[index] - hand[index], index


def _nearest(hand: FloatArray, tip: FloatArray, expected: FloatArray) -> int:
    """The sample (T,) at which ``tip`` is nearest ``hand + expected`` (NaN rows skipped)."""
    distance = np.linalg.norm(tip - hand - expected, axis=1)
    if not np.isfinite(distance).any():
        raise ValueError("hand: expected at least one finite row, got none")
    return int(np.nanargmin(distance))


def task_offsets(tracks: Sequence[tuple[FloatArray, FloatArray, int]],
                 max_rounds: int = MAX_ROUNDS) -> FloatArray:
    """Offsets (n, 3) m of one task's demonstrations, each at its meeting moment.

    The moment is where the fingertip comes nearest the object, which sits at the
    task's mean offset from the hand; the mean is not known in advance, so it is
    found by fixed-point iteration, until no demonstration's moment changes (at
    most ``max_rounds`` rounds). The first mean is taken when both partners have
    arrived (a moment a shift of the tracker cannot move), so the result moves by
    exactly -c when the tracked hand is shifted by c.

    Parameters
    ----------
    tracks : sequence of (hand (T, 3) m, fingertip (T, 3) m, arrival index)
        The arrival: the motion's end (:func:`sandbox.core.fitting.motion_end`).
    """
    moments = None
    expected = np.nanmean([tip[_finite_near(hand, i)] - hand[_finite_near(hand, i)]
                           for hand, tip, i in tracks], axis=0)
    for _ in range(max_rounds):
        found = [_nearest(hand, tip, expected) for hand, tip, _ in tracks]
        offsets = np.array([tip[i] - hand[i] for (hand, tip, _), i in zip(tracks, found)])
        if found == moments:
            break
        moments, expected = found, offsets.mean(axis=0)
    return offsets


def learn_geometry(demos: Sequence, *, max_offset: float = MAX_OFFSET_M) -> MeetingGeometry:
    """Per-task meeting geometry of ``demos`` (those that :func:`carries_geometry`).

    Returns
    -------
    MeetingGeometry
        ``source="default"`` (:data:`DEFAULT_OFFSET`) when no demonstration carries one.

    Raises
    ------
    ValueError
        Naming the trials whose offset at the meeting exceeds ``max_offset`` m (a
        unit or frame error), or the tasks none of whose demonstrations carries a
        geometry while others do.
    """
    from sandbox.core.fitting import motion_end
    from sandbox.robot import BaxterKinematics

    tasks = list(dict.fromkeys(str(d.task) for d in demos))
    usable = [d for d in demos if carries_geometry(d) and _tracked(_hand(d))]
    if not usable:
        return MeetingGeometry.default(tasks)
    kin = BaxterKinematics()
    by_task: dict[str, list] = {}
    for d in usable:
        by_task.setdefault(str(d.task), []).append(d)
    tol = {"joint": SETTLE_TOL, "task": SETTLE_TOL_M}
    offsets = {task: task_offsets([(_hand(d), _tip(d, kin), motion_end(
        d.times, d.robot, tol[getattr(d, "robot_space", "joint")], _hand(d), ARRIVE_TOL))
                                   for d in group])
               for task, group in by_task.items()}
    far = [f"{getattr(d, 'source', '') or d.task} ({np.linalg.norm(off):.2f} m)"
           for task, group in by_task.items() for d, off in zip(group, offsets[task])
           if np.linalg.norm(off) > max_offset]
    if far:
        raise ValueError(f"demos: expected the fingertip within {max_offset} m of the tracked "
                         f"hand at the meeting, got {len(far)} farther (a unit or frame "
                         f"error?): {', '.join(far[:5])}{' ...' if len(far) > 5 else ''}")
    missing = [t for t in tasks if t not in offsets]
    if missing:
        raise ValueError(f"tasks {missing}: expected a demonstration with Baxter's robot "
                         "trajectory to learn where the handover happens, got none")
    return MeetingGeometry({t: _task_geometry(offsets[t]) for t in tasks})


def _tracked(hand: FloatArray | None) -> bool:
    """Whether a demo's hand has a finite row (a meeting can be found)."""
    return hand is not None and bool(np.isfinite(hand).all(axis=1).any())


def _finite_near(hand: FloatArray, index: int) -> int:
    """The sample nearest ``index`` whose hand row is finite (``ValueError`` if none)."""
    ok = np.flatnonzero(np.isfinite(hand).all(axis=1))
    if ok.size == 0:
        raise ValueError("hand: expected at least one finite row, got none")
    return int(ok[np.argmin(np.abs(ok - index))])


def _hand(demo) -> FloatArray | None:
    """The demo's tracked hand (T, 3) m: its ``hand`` modality, or the first three human
    dims when it names no modality; None without a hand."""
    human = np.asarray(demo.human, dtype=np.float64)
    modalities = getattr(demo, "modalities", None)
    if not modalities:
        return human[:, :3] if human.ndim == 2 and human.shape[1] >= 3 else None
    start = 0
    for m in modalities:
        if m.name == "hand" and m.kind == "position" and len(m.dims) == 3:
            return human[:, start:start + 3]
        start += len(m.dims)
    return None


def _task_geometry(offsets: FloatArray) -> TaskGeometry:
    cov = np.cov(offsets.T) if len(offsets) > 1 else np.zeros((3, 3))
    return TaskGeometry(offsets.mean(axis=0), (cov + cov.T) / 2, len(offsets))


def attach_geometry(model, demos: Sequence):
    """Store :func:`learn_geometry` of ``demos`` in ``model.session``; returns ``model``.

    A geometry that falls back to the default is not stored (the model then says
    so through :func:`geometry_of`).
    """
    geometry = learn_geometry(demos)
    session = dict(getattr(model, "session", None) or {})
    session.pop(GEOMETRY_KEY, None)
    if geometry.source == "learned":
        session[GEOMETRY_KEY] = geometry.to_dict()
    model.session = session
    return model


def geometry_of(model, *, warn: bool = False) -> tuple[MeetingGeometry, str | None]:
    """The meeting geometry a model carries, or the default with a note that says why.

    Parameters
    ----------
    model : IProMP
        A fitted model (a loaded file, or one passed through :func:`attach_geometry`).
    warn : bool
        Also issue the note as a :class:`UserWarning`.

    Returns
    -------
    geometry : MeetingGeometry
    note : str or None
        None for a learned geometry; otherwise why the default is used.
    """
    entry = (getattr(model, "session", None) or {}).get(GEOMETRY_KEY)
    if entry is not None:
        return MeetingGeometry.from_dict(entry), None
    note = (f"the model carries no meeting geometry (its demonstrations have no Baxter arm "
            f"reaching the hand, or its file predates the geometry); the object rides at the "
            f"default offset "
            f"{np.round(DEFAULT_OFFSET, 3).tolist()} m from the tracked hand. Refit to learn it.")
    if warn:
        warnings.warn(note, UserWarning, stacklevel=2)
    return MeetingGeometry.default(getattr(model, "tasks", ())), note
