"""Keyboard teleoperation of the human hand: the robot anticipates live in the browser.

The terminal is switched to character mode (no Enter needed; Ctrl-C still
works) and each key changes the teleoperated hand of the environment
(``reset(options={"source": "teleop"})``, :class:`~sandbox.envs.teleop.TeleopMotion`):

======  ============================================================================
key     effect
======  ============================================================================
w / s   hand toward / away from Baxter (-x / +x)
a / d   hand to Baxter's left / right (+y / -y)
r / f   hand up / down (+z / -z)
x       halt the hand (a direction key opposite to the motion halts that axis only)
+ / -   hand speed x1.5 / /1.5 (0.02 - 0.6 m/s)
c       slow motion on / off: the clock runs at 1/4 of real time (time to aim; the hand
        and the robot move as usual in simulated time)
space   start / stop the clock (the first episode starts stopped unless asked otherwise)
n       reset: a new episode, the hand back at the start, the clock stopped (press space)
h       this help
q       quit (also Ctrl-C)
======  ============================================================================

:func:`run_teleop` runs the loop (one :func:`~sandbox.episodes.rollout.rollout` per
episode): read the keys, step the environment (its ``"human"`` render mode
shows it live, paced to real time), draw the
predictor's overlays and panel, and print a status line at every predictor
update (:func:`status_line`): the time, the hand (true and as the tracker saw it),
the recognised task and posterior, the gripper-to-hand distance and the robot's
predicted meeting point (where its plan ends), to aim the hand without looking at
the browser; "unsure / unknown motion" when the motion is unlike the training demos.

With a recorder (:class:`sandbox.episodes.demos_recording.DemoRecorder`, ``play
--record-demos DIR --task NAME``) every episode is also saved as a
demonstration when it ends: ``n``, ``q``, the handover or the time limit.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from sandbox.episodes.keys import Keyboard, split_keys  # noqa: F401  (re-exported)
from sandbox.episodes.policy import Policy, beliefs_of
from sandbox.episodes.rollout import Step, rollout
from sandbox.robot import TIP_LINK

#: Key -> (axis, direction) of the hand motion.
MOVES = {"w": (0, -1), "s": (0, 1), "a": (1, 1), "d": (1, -1), "r": (2, 1), "f": (2, -1)}
SPEED_RANGE = (0.02, 0.6)
#: Simulated seconds per wall-clock second in slow motion (key ``c``).
SLOW_RATE = 0.25
#: Said on the status line when the predictor finds the motion unlike its training demos.
UNSURE = "unsure / unknown motion"
HELP_TEXT = """\
  w / s   hand toward / away from Baxter (-x / +x)
  a / d   hand to Baxter's left / right (+y / -y)
  r / f   hand up / down (+z / -z)
  x       halt the hand (the key opposite to a motion halts that axis)
  + / -   hand speed x1.5 / /1.5
  c       slow motion on / off (the clock at 1/4 of real time)
  space   start / stop the clock
  n       reset (new episode; press space to start)   h  help   q  quit (or Ctrl-C)"""


@dataclass
class TeleopState:
    """What the keys have set so far.

    Attributes
    ----------
    direction : ndarray, shape (3,)
        -1, 0 or +1 per axis.
    speed : float
        Hand speed along each moving axis (m/s).
    running : bool
        Whether the clock runs.
    slow : bool
        Slow motion: the clock runs at :data:`SLOW_RATE` of real time.
    """

    direction: np.ndarray = field(default_factory=lambda: np.zeros(3))
    speed: float = 0.2
    running: bool = False
    slow: bool = False

    @property
    def rate(self) -> float:
        """Simulated seconds per wall-clock second: 1, or :data:`SLOW_RATE` in slow motion."""
        return SLOW_RATE if self.slow else 1.0

    @property
    def velocity(self) -> np.ndarray:
        """Commanded hand velocity (3,) m/s."""
        return self.direction * self.speed

    def apply(self, key: str) -> str | None:
        """Apply one key; return the action for the loop (``"quit"``, ``"reset"``,
        ``"help"``, ``"move"``, ``"clock"``, ``"slow"``) or None for an unknown key.

        ``n`` (reset) also stops the clock: the next episode waits for space.
        """
        if key in MOVES:
            axis, sign = MOVES[key]
            self.direction[axis] = 0.0 if self.direction[axis] == -sign else sign
            return "move"
        if key == "x":
            self.direction[:] = 0.0
            return "move"
        if key in ("+", "=", "-"):
            factor = 1.5 if key in "+=" else 1 / 1.5
            self.speed = float(np.clip(self.speed * factor, *SPEED_RANGE))
            return "move"
        if key == " ":
            self.running = not self.running
            return "clock"
        if key == "c":
            self.slow = not self.slow
            return "slow"
        if key == "n":
            self.running = False
            return "reset"
        return {"q": "quit", "h": "help", "?": "help"}.get(key)


def status_line(t: float, hand, seen, beliefs, *, gripper=None, meeting=None) -> str:
    """``t=... hand=(x,y,z) seen=(x,y,z) m task=... p[...] T=...s gripper-hand=...m
    meet=(x,y,z)`` for the terminal.

    Parameters
    ----------
    t : float
        Time (s).
    hand, seen : array_like, shape (3,)
        The true hand position and the tracker's measurement the policy received (m).
    beliefs : Beliefs
        A policy's :class:`~sandbox.episodes.policy.Beliefs` (or a predictor):
        its task, posterior and duration estimate are shown, and "unsure /
        unknown motion" when its ``familiar`` (if it has one) is False.
    gripper : array_like, shape (3,), optional
        The gripper's fingertip (m): adds its distance to the hand (m).
    meeting : array_like, shape (3,), optional
        The robot's predicted meeting point (m), e.g. :func:`meeting_point`.
    """
    post = beliefs.task_posterior
    probs = " ".join(f"{k}={v:.2f}" for k, v in post.items())
    hand = np.asarray(hand, dtype=float)
    line = (f"t={t:5.2f}s hand={_xyz(hand)} seen={_xyz(seen)} m task={beliefs.task or '-'} "
            f"p[{probs}] T={beliefs.duration:.2f}s")
    if gripper is not None:
        line += f" gripper-hand={np.linalg.norm(np.asarray(gripper, dtype=float) - hand):.3f}m"
    if meeting is not None:
        line += f" meet={_xyz(meeting)}"
    if getattr(beliefs, "familiar", None) is False:
        line += f" {UNSURE}"
    return line


def _xyz(p) -> str:
    x, y, z = (float(v) for v in p)
    return f"({x:+.3f},{y:+.3f},{z:+.3f})"


def meeting_point(beliefs, kinematics, link: str = TIP_LINK) -> np.ndarray:
    """Where the robot's current plan ends (3,) m: the fingertip at its last mean joints.

    ``beliefs`` is a policy's :class:`~sandbox.episodes.policy.Beliefs` (or a
    predictor: anything with ``plan()``); ``kinematics`` is a
    :class:`~sandbox.robot.BaxterKinematics` (``fk(q, link=...)``).
    """
    _, means, _ = beliefs.plan()
    end = np.asarray(means[-1], dtype=float)
    return end if end.shape[-1] == 3 else kinematics.fk(end, link=link)   # task space: as is


def _meetings(policy) -> str:
    """Where each task's hand ends, on average over the model's demos (for ``h``)."""
    model = getattr(getattr(policy, "predictor", None), "model", None)
    if model is None:
        return ""
    from sandbox.core.promp import trajectory_distribution

    lines = ["", "  each task's hand ends (m, Baxter's base frame; aim for it):"]
    for task in model.task_models:
        mean, _ = trajectory_distribution(task.weights.dims(slice(0, 3)), model.basis,
                                          np.ones(1))
        lines.append(f"    {task.name:12s} {_xyz(mean[0] * model.scale[:3])}")
    return "\n".join(lines)


def _outcome(info: dict, t: float) -> str:
    if info.get("is_success"):
        return f"handover at {info['handover_time']:.2f} s"
    return f"no handover by {t:.2f} s (time limit)"


def run_teleop(env: Any, policy: Policy, keyboard: Keyboard, *, seed: int = 0,
               running: bool = False, out: Callable[[str], None] = print,
               recorder: Any = None) -> int:
    """The teleop loop; returns the number of episodes played.

    One :func:`~sandbox.episodes.rollout.rollout` per episode: the keys are read before
    each step (waited for while the clock is stopped); ``n`` and ``q`` end it. The loop
    ends on ``q``, or when the input is closed and the episode is over.

    Parameters
    ----------
    env : gymnasium.Env
        A handover environment made with ``render_mode="human"`` (its viewer is used).
    policy : Policy
        Drives the robot; its beliefs are drawn in the viewer (overlays, panel)
        and printed on the status line.
    keyboard : Keyboard
        Where keys come from.
    seed : int
        Seed of the first episode (then seed + 1, ...).
    running : bool
        Start the clock of the first episode at once (default: press space); after
        ``n`` the clock always waits for space.
    out : callable
        Prints a line.
    recorder : DemoRecorder, optional
        Saves each episode as a demonstration when it ends (and says where).
    """
    loop = _Loop(env, policy, TeleopState(running=running), keyboard, seed, out, recorder)
    while True:
        last = rollout(env, policy, seed=seed + loop.episodes, options={"source": "teleop"},
                       on_reset=loop.started, on_step=loop.stepped, until=loop.wait)
        ending = loop.ending if not last.done else loop.after_episode()
        loop.save()
        if ending != "reset":
            return loop.episodes


class _Loop:
    """The state of :func:`run_teleop` between keys and steps."""

    def __init__(self, env, policy, state: TeleopState, keyboard: Keyboard, seed: int, out,
                 recorder=None) -> None:
        from sandbox.robot import BaxterKinematics

        self.env, self.policy, self.state, self.seed, self.out = env, policy, state, seed, out
        self.keyboard, self.recorder = keyboard, recorder
        self.kinematics, self.episodes = BaxterKinematics(), 0
        self.overlay: Any = None
        self._pending: list[str] = []

    def started(self, step: Step) -> None:
        """A new episode (the rollout's reset): the hand at the start, the viewer's overlay."""
        self.obs, self.episodes = step.obs, self.episodes + 1
        self.state.direction[:] = 0.0
        self.n_updates, self.frame, self.ending = 0, 0, ""
        if self.recorder is not None:
            self.recorder.start()
            self._record(0.0)
        self.out(f"episode {self.episodes}: the hand is at the start; "
                 + ("the clock runs" if self.state.running else "press space to start the clock")
                 + ("; slow motion is still on (c: off)" if self.state.slow else ""))
        self._edges: set[tuple[int, int]] = set()
        if self.overlay is None:
            self.viewer = self.env.unwrapped.viewer
            self.overlay = self.viewer.add_overlay(
                beliefs_of(self.policy).tasks, rng=np.random.default_rng(self.seed),
                title="teleop: keys in the terminal (h: help)")
            self.out("keys:\n" + HELP_TEXT)
            arm = getattr(self.env.unwrapped.robot, "name", "baxter")
            if arm != "baxter":                      # another arm: its own fingertip
                from sandbox.robot.retarget import Retargeter

                self.overlay.executed_tip = Retargeter(arm).tip
        self.overlay.restart(beliefs_of(self.policy), truth=self.env.unwrapped.human_intent(0.0))

    def wait(self, step: Step) -> bool:
        """Before a step: apply the keys, wait while the clock is stopped; True on ``n``/``q``."""
        while True:
            keys = self._read(0.0 if self.state.running else 0.05)
            for i, key in enumerate(keys):
                action = self.key(key)
                if action in ("quit", "reset"):
                    self.ending, self._pending = action, keys[i + 1:]
                    return True
            if self.keyboard.closed and not self.state.running:
                self.state.running = True  # no more keys: play the episode out
                self.viewer.restart_pacing()
                self.out("> input ended: the clock runs the episode out (the hand keeps its "
                         "last command)")
            if self.state.running:
                self.env.unwrapped.motion.set_velocity(self.state.velocity)
                return False

    def stepped(self, step: Step) -> None:
        """After a step: record the hand, draw, report."""
        env, beliefs = self.env.unwrapped, beliefs_of(self.policy)
        self.obs, t = step.obs, step.time
        self._record(t)
        self._say_edges(env.motion, t)
        if int(round(t * self.viewer.scene.timeline.fps)) != self.frame:
            self.frame = int(round(t * self.viewer.scene.timeline.fps))
            self.overlay.show(beliefs, t, executed_q=self.obs["q"], truth=env.human_intent(t))
        if beliefs.n_updates > self.n_updates:
            self.n_updates = beliefs.n_updates
            gripper = (self.kinematics.fk(self.obs["q"], link=TIP_LINK)
                       if self.obs["q"].shape == (7,) and env.robot.name == "baxter"
                       else env.robot.tip_position())
            meeting = meeting_point(beliefs, self.kinematics)
            self.out(status_line(t, env.motion.position(t), self.obs["hand"], beliefs,
                                 gripper=gripper, meeting=meeting))
        if step.done:
            info = step.info
            self.out(f"episode over: {_outcome(info, t)}, gripper {100 * info['distance']:.1f} cm "
                     f"from the object, task {beliefs.task}; n: new episode, q: quit")
            self.save()

    def _say_edges(self, motion, t: float) -> None:
        """Say once when the hand stops at an edge of the workspace it is driven toward."""
        edges = getattr(motion, "edges", None)
        if edges is None:
            return
        for axis, side, value in edges(t):
            if (axis, side) not in self._edges:
                self._edges.add((axis, side))
                self.out(f"> the hand stopped at the workspace's edge ({'xyz'[axis]} = "
                         f"{value:+.2f} m); {'xyz'[axis]} keys the other way move it back")

    def after_episode(self) -> str:
        """Keys after the episode ended, until ``n`` (``"reset"``) or ``q`` / closed input."""
        while True:
            keys = self._read(0.05)
            for i, key in enumerate(keys):
                action = self.key(key)
                if action in ("quit", "reset"):
                    self._pending = keys[i + 1:]
                    return action
            if self.keyboard.closed:
                return "quit"

    def _read(self, timeout: float) -> list[str]:
        """Keys left from the last chunk (after an ``n``), else the keyboard's."""
        if self._pending:
            keys, self._pending = self._pending, []
            return keys
        return self.keyboard.read(timeout)

    def key(self, key: str) -> str | None:
        """Apply a key; return its action."""
        action = self.state.apply(key)
        if action == "help":
            self.out("keys:\n" + HELP_TEXT + _meetings(self.policy))
        elif action == "reset":
            self.save()
        elif action == "move":
            v = self.state.velocity
            self.out(f"> {key}: hand velocity ({v[0]:+.2f}, {v[1]:+.2f}, {v[2]:+.2f}) m/s")
        elif action == "clock":
            self.viewer.restart_pacing()  # real time resumes from here, not from the reset
            self.out("> clock " + ("runs" if self.state.running else "stopped"))
        elif action == "slow":
            self.viewer.set_rate(self.state.rate)
            self.out(f"> slow motion {'on' if self.state.slow else 'off'}: the clock runs at "
                     f"x{self.state.rate:g} real time")
        return action

    def _record(self, t: float) -> None:
        """Give the recorder the hand at time ``t`` (s): true and as the tracker saw it."""
        if self.recorder is not None:
            self.recorder.add(t, self.env.unwrapped.motion.position(t), self.obs["hand"])

    def save(self) -> None:
        """Save the episode as a demonstration (once), if recording."""
        if self.recorder is not None:
            line = self.recorder.finish()
            if line:
                self.out(line)
