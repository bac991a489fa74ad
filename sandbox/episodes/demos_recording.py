"""Demonstrations recorded with the keyboard teleop: ``play --record-demos DIR --task NAME``.

A person drives the hand (:mod:`sandbox.episodes.keyboard`) to a handover place of
their choosing; each episode becomes one demonstration in the recorded CSV
layout, ``DIR/NAME/NNN.csv`` (:mod:`sandbox.data.writer`), so that ``fit
--data DIR`` learns the new tasks like the recorded ones.

What a file holds (:func:`teleop_trial`):

* the rows from ``lead_s`` before the hand starts moving to ``tail_s`` after
  it stops (the recordings run on 0.6 s after the motion on average), times
  from 0, one row per control step (50 Hz);
* ``human_left_hand_x/y/z``: the hand as the tracker saw it (the
  environment's observation: 30 Hz frames, sample-and-hold, 2 mm noise), as in
  the recordings;
* ``left_s0 ... left_w2``: the robot's paired motion, the synthetic
  generator's construction (:func:`sandbox.data.synthetic.robot.robot_meeting`):
  inverse kinematics of the gripper at the point where the hand stopped, a
  minimum-jerk arm motion from home that starts when the hand starts and ends
  when it stops (at least ``min_robot_s`` long);
* ``baxter_left_hand_x/y/z``: forward kinematics of those joints
  (``left_hand_link``); ``right_s0 ... right_w2``: the right arm's held posture;
* nothing else: the teleop has no tracked elbow, shoulder, head or torso and no
  EMG, so those columns are empty. The loader reads them as missing: the files
  load with ``observe="hand"``, and asking for ``arm`` or ``emg`` skips every
  file with the reason.

The robot's motion in the environment during recording (the predictor of
``play``) is not what is saved: a demonstration pairs the hand with the robot
a kinesthetic teacher would have shown.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from sandbox.data.spec import ROBOT_COLUMNS
from sandbox.data.synthetic.robot import kinematics, robot_meeting
from sandbox.data.writer import RIGHT_ARM_COLUMNS, next_trial_path, write_trial
from sandbox.episodes.policy import Beliefs
from sandbox.validation import FloatArray, check_array, check_positive, check_times

#: Right-arm posture of the recordings and of the environment (rad), ``right_s0 ... right_w2``.
Q_RIGHT = (-0.285, -1.031, 0.907, 1.601, -0.482, 1.124, -0.208)
_TASK_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$")


def check_task_name(name: object) -> str:
    """``name`` if it can be a task folder: letters, digits, ``_ . -``, at most 64 characters."""
    if not isinstance(name, str) or not _TASK_NAME.match(name):
        raise ValueError(f"--task: expected a name of letters, digits, '_', '.' or '-' "
                         f"(starting with a letter or digit, at most 64), got {name!r}")
    return name


def motion_span(hand: FloatArray, still_m: float = 1e-6) -> tuple[int, int]:
    """Rows where the hand starts and stops moving: ``(first, last)`` indices.

    ``first`` is the last row before the first step longer than ``still_m``
    (m), ``last`` the row after the last such step; ``(0, 0)`` if it never moves.
    """
    moving = np.flatnonzero(np.linalg.norm(np.diff(hand, axis=0), axis=1) > still_m)
    if moving.size == 0:
        return 0, 0
    return int(moving[0]), int(moving[-1] + 1)


def teleop_trial(times: ArrayLike, hand: ArrayLike, seen: ArrayLike, *, lead_s: float = 0.1,
                 tail_s: float = 0.6, min_reach_m: float = 0.05, min_robot_s: float = 0.5,
                 ik_tol: float = 0.01) -> tuple[FloatArray, dict[str, FloatArray], dict]:
    """One teleop episode as a trial: its times, its columns and what was found.

    Parameters
    ----------
    times : array_like, shape (T,)
        Episode times (s), strictly increasing.
    hand, seen : array_like, shape (T, 3)
        The true hand and the tracker's measurement of it (m), Baxter's base frame.
    lead_s, tail_s : float
        Time kept before the hand starts moving and after it stops (s).
    min_reach_m, min_robot_s : float
        Shortest distance (m) from the start to where the hand stops; shortest robot motion (s).
    ik_tol : float
        Required gripper position error (m) at the meeting point.

    Returns
    -------
    times : ndarray, shape (n,)
        Trial times (s) from 0.
    columns : dict of str to ndarray, each shape (n,)
        Columns of :data:`sandbox.data.writer.RECORDED_COLUMNS` (see the module docstring).
    info : dict
        ``meeting`` (3,) m, where the hand stopped; ``ik_error`` m; ``reach_time``
        (start, stop) s in trial time; ``duration`` s.

    Raises
    ------
    ValueError
        The hand moved less than ``min_reach_m``, or stopped out of the robot's reach.
    """
    times = check_times(times, "times")
    hand = check_array(hand, "hand", 2, shape=(times.size, 3))
    seen = check_array(seen, "seen", 2, shape=(times.size, 3))
    first, last = motion_span(hand)
    reach = float(np.linalg.norm(hand[last] - hand[0]))
    if reach < check_positive(min_reach_m, "min_reach_m"):
        raise ValueError(f"the hand stopped {100 * reach:.1f} cm from its start; expected a "
                         f"reach of at least {100 * min_reach_m:g} cm to a handover place")
    t_on, t_stop = times[first], times[last]
    t_off = max(t_stop, t_on + check_positive(min_robot_s, "min_robot_s"))
    lead_s = check_positive(lead_s, "lead_s", allow_zero=True)
    tail_s = check_positive(tail_s, "tail_s", allow_zero=True)
    keep = (times >= t_on - lead_s - 1e-9) & (times <= t_off + tail_s + 1e-9)  # rounding
    t0 = times[keep][0]
    out_t = times[keep] - t0
    q, error = robot_meeting(out_t, hand[last], t_on - t0, t_off - t0, ik_tol=ik_tol)
    wrist = kinematics().fk(q, link="left_hand_link")
    columns = {
        **{f"human_left_hand_{a}": seen[keep, i] for i, a in enumerate("xyz")},
        **{f"baxter_left_hand_{a}": wrist[:, i] for i, a in enumerate("xyz")},
        **{name: q[:, i] for i, name in enumerate(ROBOT_COLUMNS)},
        **{name: np.full(out_t.size, v) for name, v in zip(RIGHT_ARM_COLUMNS, Q_RIGHT)},
    }
    info = {"meeting": hand[last].copy(), "ik_error": error,
            "reach_time": (t_on - t0, t_stop - t0), "duration": float(out_t[-1])}
    return out_t, columns, info


class DemoRecorder:
    """Collects a teleop episode's hand and saves it as a demonstration of one task.

    Parameters
    ----------
    root : str or Path
        The dataset folder; files go to ``root/task/NNN.csv``.
    task : str
        The task's name (:func:`check_task_name`).
    **options
        Passed to :func:`teleop_trial` (``lead_s``, ``tail_s``, ...).

    Attributes
    ----------
    saved : list of Path
        The files written so far.
    """

    def __init__(self, root: str | Path, task: str, **options) -> None:
        self.folder = Path(root) / check_task_name(task)
        if self.folder.exists() and not self.folder.is_dir():
            raise ValueError(f"--record-demos: expected a folder for {self.folder}, got a file")
        self.task, self.options = task, options
        self.saved: list[Path] = []
        self._rows: list[tuple[float, FloatArray, FloatArray]] = []

    def start(self) -> None:
        """Forget the rows of the previous episode."""
        self._rows = []

    def add(self, t: float, hand: ArrayLike, seen: ArrayLike) -> None:
        """One row: time (s), true hand (3,) m, hand seen by the tracker (3,) m."""
        if self._rows and t <= self._rows[-1][0]:
            return  # the same step twice (a reset's first row): keep the first
        self._rows.append((float(t), np.array(hand, dtype=float), np.array(seen, dtype=float)))

    def finish(self) -> str | None:
        """Save the episode collected since :meth:`start`; a line saying what happened.

        None when there is nothing to save (no rows, or already saved).
        """
        rows, self._rows = self._rows, []
        if len(rows) < 2:
            return None
        t, hand, seen = (np.array(c) for c in zip(*rows))
        try:
            times, columns, info = teleop_trial(t, hand, seen, **self.options)
        except ValueError as error:
            return f"not saved as a demo of '{self.task}': {error}"
        path = write_trial(next_trial_path(self.folder), times, columns)
        self.saved.append(path)
        x, y, z = info["meeting"]
        return (f"saved demo {len(self.saved)} of '{self.task}': {path} ({info['duration']:.2f} s,"
                f" hand stopped at ({x:+.3f},{y:+.3f},{z:+.3f}) m, the robot's demo meets it "
                f"within {1000 * info['ik_error']:.1f} mm)")


class HeldRobot:
    """A policy whose predictor runs (status line, overlays) while the robot holds still.

    While new tasks are recorded the robot knows none of them; held at home
    with its gripper open, it never takes the object and cuts a demonstration
    short.

    Parameters
    ----------
    policy : IProMPPolicy
        Its predictor is fed every observation; its other attributes are this one's.
    q : array_like, shape (7,)
        The held joint targets (rad); default the home pose :data:`~sandbox.robot.Q_HOME`.
    """

    def __init__(self, policy, q: ArrayLike | None = None) -> None:
        from sandbox.robot import Q_HOME

        self.policy = policy
        self._action = np.append(check_array(Q_HOME if q is None else q, "q", 1, shape=(7,)),
                                 -1.0)

    def __getattr__(self, name: str):
        return getattr(self.policy, name)

    def reset(self) -> None:
        """Reset the wrapped policy."""
        self.policy.reset()

    @property
    def beliefs(self) -> Beliefs:
        """The wrapped policy's beliefs (its predictor runs on)."""
        return self.policy.beliefs

    def __call__(self, obs) -> FloatArray:
        """The held action (8,): joint targets (rad), gripper open (-1)."""
        self.policy(obs)
        return self._action.copy()
