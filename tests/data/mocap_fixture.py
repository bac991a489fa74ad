"""A motion-capture style recorded set, generated: the layout of issue 28 (test fixture).

Human-human handover sets often come as one folder per trial holding one CSV
per body segment (``giver_RHand_pose.csv`` with columns ``x, y, z, q0..q3``),
no time column (a fixed rate, here 120 Hz), millimetres in a Z-up world frame
of their own, the object of each handover in a label file, and long windows
(7.5 s) holding a pick-up, the reach, the transfer and a retreat.
:func:`write_mocap_set` writes such a set from the synthetic
handovers of three objects (``synthetic:objects``: box, glasses case, tape; the
hand without the Kinect's artefacts, plus 1 mm of mocap jitter):

- ``<root>/trial_NN/giver_RHand_pose.csv``: the giving hand (mm, world frame);
- ``<root>/trial_NN/taker_RHand_pose.csv``: Baxter's gripper tip (mm, world frame);
- ``<root>/trial_NN/baxter_left_arm.csv``: the robot's seven joints ``left_s0 ... left_w2``;
- ``<root>/labels.csv``: ``trial, object``.

With ``taker="human"`` the set is human-human (:data:`HUMAN_SPEC` reads it):
``taker_RHand_pose.csv`` is a receiving *hand* and there is no robot file. It
rests at Baxter's gripper tip's home place (the taker's side), starts its own
minimum-jerk reach 0.1-0.4 s after the giver's, arrives 0-0.3 s after the giver
did, at the giver's hand plus 6-10 cm toward the taker's side (:data:`HUMAN_SIDE`;
the object between the palms, beyond the 5 cm grasp radius), holds 1 s and takes the object back to
rest in 1 s.

Each window: the hand rests 0.5 s at a pick-up place, lifts the object to the
reach's start in 1 s (minimum jerk), waits 1 s, reaches (the synthetic demo, at
2.5 s), holds 0.5 s at the handover, withdraws 25 cm straight away from the
taker in 1 s, and rests; the robot waits at its first configuration, follows the
demo, holds 1.5 s and takes the object home in 1 s.

:data:`SPEC` is the spec file that reads it (the docs page "Bring your own
recordings" shows the same text). Run as a script: ``python
tests/data/mocap_fixture.py DIR`` writes the set into DIR.
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import numpy as np

#: Rate of the files (Hz); they carry no time column.
RATE_HZ = 120.0
#: Length of a window (s; longer when a reach needs it).
WINDOW_S = 7.5
#: When the reach starts in each window (s).
REACH_AT_S = 2.5
#: The world-to-base transform of the set: p_base = R_z(YAW) p_world + TRANSLATION.
YAW_DEG = 90.0
TRANSLATION = np.array([0.35, -1.2, -0.93])
ROBOT = ("left_s0", "left_s1", "left_e0", "left_e1", "left_w0", "left_w1", "left_w2")
SPEC = """\
# mocap.yaml
rate_hz: 120                      # no time column: row i is at i / 120 s
units: mm                         # positions converted to metres
files:                            # one file per body segment in each trial folder
  giver: giver_RHand_pose.csv
  robot: baxter_left_arm.csv
labels: {file: labels.csv, trial: trial, task: object}
robot: [robot.left_s0, robot.left_s1, robot.left_e0, robot.left_e1,
        robot.left_w0, robot.left_w1, robot.left_w2]      # Baxter's joints (rad)
modalities:
  hand: {columns: [giver.x, giver.y, giver.z], kind: position}
frame: {translation: [0.35, -1.2, -0.93], yaw: 90, up: z}
segment:
  start: {rule: onset, speed: 0.05, distance_m: 0.15, before_s: 0.1}
  end: {rule: approach, within_m: 0.005, hold_s: 0.5}
resample_hz: 60
"""
#: The spec of the human-human variant: the receiving hand is the robot part, in task space.
HUMAN_SPEC = (SPEC.replace("  robot: baxter_left_arm.csv", "  taker: taker_RHand_pose.csv")
              .replace("robot: [robot.left_s0, robot.left_s1, robot.left_e0, robot.left_e1,\n"
                       "        robot.left_w0, robot.left_w1, robot.left_w2]      # Baxter's "
                       "joints (rad)",
                       "robot: {columns: [taker.x, taker.y, taker.z], space: task}  # a hand"))
#: Range of the receiving hand's distance from the giving hand at the meeting (m).
HUMAN_GAP_M = (0.06, 0.10)
#: Direction (base frame) from the giving hand to the receiving one at the meeting: toward
#: the taker's side, as a person holds an object out to another, the same in every trial.
HUMAN_SIDE = np.array([-0.5, 0.85, 0.0]) / np.linalg.norm([-0.5, 0.85, 0.0])


def _rotation(yaw_deg: float) -> np.ndarray:
    c, s = np.cos(np.radians(yaw_deg)), np.sin(np.radians(yaw_deg))
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def to_world(points: np.ndarray) -> np.ndarray:
    """Base-frame points (n, 3) m -> the set's world frame (n, 3) m."""
    return (points - TRANSLATION) @ _rotation(YAW_DEG)


def _min_jerk(a: np.ndarray, b: np.ndarray, n: int) -> np.ndarray:
    tau = np.linspace(0.0, 1.0, n)[:, None]
    return a + (b - a) * (10 * tau**3 - 15 * tau**4 + 6 * tau**5)


def _hold(a: np.ndarray, n: int) -> np.ndarray:
    return np.repeat(np.asarray(a, dtype=float)[None], n, axis=0)


def _tip(robot: np.ndarray) -> np.ndarray:
    """Baxter's gripper tip (n, 3) m for joints (n, 7) rad."""
    from sandbox.data.synthetic.robot import kinematics
    from sandbox.robot import TIP_LINK

    return kinematics().fk(robot, link=TIP_LINK)


def _window(demo, meet: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, int]:
    """Hand (n, 3) m and robot (n, 7) rad of one 7.5 s window at 120 Hz, base frame, and
    the number of rows of the reach; the hand withdraws away from ``meet`` (m; default
    the gripper tip at the end of the reach)."""
    t = np.arange(0.0, demo.duration, 1.0 / RATE_HZ) + demo.times[0]
    clean = demo.meta["clean_human"]                   # the hand without the Kinect's artefacts
    hand = np.column_stack([np.interp(t, demo.times, y) for y in clean.T])
    robot = np.column_stack([np.interp(t, demo.times, q) for q in demo.robot.T])
    start, end, home = hand[0], hand[-1], robot[0]
    pickup = start + np.array([0.05, -0.25, -0.30])
    r = int(RATE_HZ)
    pre = [_hold(pickup, r // 2), _min_jerk(pickup, start, r), _hold(start, r)]
    n_post = max(int(round(WINDOW_S * RATE_HZ)) - sum(len(p) for p in pre) - len(t), 5 * r // 2)
    tip = _tip(robot[-1:])[0] if meet is None else meet
    away = end + 0.25 * (end - tip) / np.linalg.norm(end - tip)   # straight away from the taker
    post_hand = [_hold(end, r // 2), _min_jerk(end, away, r), _hold(away, n_post - 3 * r // 2)]
    post_robot = [_hold(robot[-1], 3 * r // 2), _min_jerk(robot[-1], home, r),
                  _hold(home, n_post - 5 * r // 2)]
    robot_all = np.vstack([_hold(home, sum(len(p) for p in pre)), robot, *post_robot])
    return np.vstack([*pre, hand, *post_hand]), robot_all, len(t)


def _taker_hand(demo, rng: np.random.Generator) -> tuple[np.ndarray, float, np.ndarray]:
    """The receiving hand (n, 3) m of a human-human window (module docstring), base frame,
    its distance from the giver's hand at the meeting (m) and where it meets (3,) m."""
    hand, robot, n_reach = _window(demo)
    r = int(RATE_HZ)
    n_pre = 5 * r // 2
    end = hand[n_pre + n_reach - 1]
    rest = _tip(robot[:1])[0]
    gap = float(rng.uniform(*HUMAN_GAP_M))
    meet = end + gap * HUMAN_SIDE
    start = n_pre + int(rng.uniform(0.1, 0.4) * RATE_HZ)
    arrive = n_pre + n_reach - 1 + int(rng.uniform(0.0, 0.3) * RATE_HZ)
    parts = [_hold(rest, start), _min_jerk(rest, meet, arrive - start + 1), _hold(meet, r),
             _min_jerk(meet, rest, r)]
    taker = np.vstack(parts)
    taker = np.vstack([taker, _hold(rest, max(len(hand) - len(taker), 0))])[:len(hand)]
    return taker, gap, meet


def _write(path: Path, header: list[str], rows: np.ndarray) -> None:
    with open(path, "w", newline="") as fh:
        out = csv.writer(fh)
        out.writerow(header)
        out.writerows([f"{v:.6f}" for v in row] for row in rows)


def write_mocap_set(root: Path, *, n_per_task: int = 8, seed: int = 0,
                    taker: str = "robot") -> dict:
    """Write the set into ``root``; return the truth of each trial.

    ``taker="human"`` writes the human-human variant (module docstring): the truth then
    also holds ``gap_m``, the receiving hand's distance from the giving hand at the meeting.

    Returns
    -------
    dict
        ``trial name -> {"task", "reach_start_s", "reach_end_s", "meeting_m"}``:
        the synthetic demo's first and last row (s from the window's first row;
        the demo ends with both at rest) and the hand there (m, base frame).
    """
    from sandbox.data.synthetic import make_dataset
    rng = np.random.default_rng(seed)
    demos = make_dataset("objects", n_per_task, np.random.default_rng(seed))
    order = rng.permutation(len(demos))          # trials not grouped by task
    root = Path(root)
    root.mkdir(parents=True, exist_ok=True)
    truth, quat = {}, np.array([1.0, 0.0, 0.0, 0.0])
    if taker not in ("robot", "human"):
        raise ValueError(f"taker: expected 'robot' or 'human', got {taker!r}")
    for k, i in enumerate(order):
        gap = None
        if taker == "human":
            tip, gap, meet = _taker_hand(demos[i], rng)
            hand, robot, n_reach = _window(demos[i], meet)
            tip = tip + rng.normal(0.0, 0.001, tip.shape)
        else:
            hand, robot, n_reach = _window(demos[i])
            tip = _tip(robot)
        hand = hand + rng.normal(0.0, 0.001, hand.shape)            # 1 mm mocap jitter
        name = f"trial_{k:02d}"
        folder = root / name
        folder.mkdir(exist_ok=True)
        pose = ["x", "y", "z", "q0", "q1", "q2", "q3"]
        for file, points in (("giver_RHand_pose.csv", hand), ("taker_RHand_pose.csv", tip)):
            _write(folder / file, pose,
                   np.column_stack([1e3 * to_world(points), _hold(quat, len(points))]))
        if gap is None:
            _write(folder / "baxter_left_arm.csv", list(ROBOT), robot)
        end = int(REACH_AT_S * RATE_HZ) + n_reach - 1
        truth[name] = {"task": demos[i].task, "reach_start_s": REACH_AT_S,
                       "reach_end_s": end / RATE_HZ, "meeting_m": hand[end].tolist()}
        if gap is not None:
            truth[name]["gap_m"] = gap
    with open(root / "labels.csv", "w", newline="") as fh:
        out = csv.writer(fh)
        out.writerow(["trial", "object"])
        out.writerows([name, t["task"]] for name, t in truth.items())
    return truth


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: python tests/data/mocap_fixture.py DIR")
    write_mocap_set(Path(sys.argv[1]))
    print(f"wrote a motion-capture style set into {sys.argv[1]}")
