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
space   start / stop the clock (the episode starts stopped unless asked otherwise)
n       reset: a new episode, the hand back at the start
h       this help
q       quit (also Ctrl-C)
======  ============================================================================

:func:`run_teleop` runs the loop: read the keys, step the environment (its
``"human"`` render mode shows it live, paced to real time), draw the
predictor's overlays, and print the hand position and the task posterior at
every predictor update.
"""

from __future__ import annotations

import os
import select
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

#: Key -> (axis, direction) of the hand motion.
MOVES = {"w": (0, -1), "s": (0, 1), "a": (1, 1), "d": (1, -1), "r": (2, 1), "f": (2, -1)}
SPEED_RANGE = (0.02, 0.6)
HELP_TEXT = """\
  w / s   hand toward / away from Baxter (-x / +x)
  a / d   hand to Baxter's left / right (+y / -y)
  r / f   hand up / down (+z / -z)
  x       halt the hand (the key opposite to a motion halts that axis)
  + / -   hand speed x1.5 / /1.5
  space   start / stop the clock
  n       reset (new episode)      h  help      q  quit (or Ctrl-C)"""


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
    """

    direction: np.ndarray = field(default_factory=lambda: np.zeros(3))
    speed: float = 0.2
    running: bool = False

    @property
    def velocity(self) -> np.ndarray:
        """Commanded hand velocity (3,) m/s."""
        return self.direction * self.speed

    def apply(self, key: str) -> str | None:
        """Apply one key; return the action for the loop (``"quit"``, ``"reset"``,
        ``"help"``, ``"move"``, ``"clock"``) or None for an unknown key."""
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
        return {"n": "reset", "q": "quit", "h": "help", "?": "help"}.get(key)


def split_keys(data: str) -> list[str]:
    """Keys in a chunk of terminal input; escape sequences (arrows...) are dropped."""
    keys, i = [], 0
    while i < len(data):
        if data[i] == "\x1b":  # ESC [ X  or  ESC O X
            i += 3 if data[i + 1:i + 2] in ("[", "O") else 1
            continue
        keys.append(data[i])
        i += 1
    return keys


class Keyboard:
    """Non-blocking key reader on a file descriptor (the terminal in character mode).

    Parameters
    ----------
    fd : int
        File descriptor to read (default: standard input).

    Attributes
    ----------
    closed : bool
        End of input reached (e.g. a pipe that was closed).
    """

    def __init__(self, fd: int | None = None) -> None:
        self.fd = sys.stdin.fileno() if fd is None else fd
        self.closed = False
        self._saved = None

    def __enter__(self) -> Keyboard:
        if os.isatty(self.fd):
            import termios
            import tty

            self._saved = termios.tcgetattr(self.fd)
            tty.setcbreak(self.fd)  # keys without Enter, no echo; Ctrl-C still interrupts
        return self

    def __exit__(self, *exc) -> None:
        if self._saved is not None:
            import termios

            termios.tcsetattr(self.fd, termios.TCSADRAIN, self._saved)

    def read(self, timeout: float = 0.0) -> list[str]:
        """Keys typed since the last call (waits up to ``timeout`` s for the first one)."""
        if self.closed:
            time.sleep(timeout)
            return []
        ready, _, _ = select.select([self.fd], [], [], timeout)
        if not ready:
            return []
        data = os.read(self.fd, 1024)
        if not data:
            self.closed = True
            return []
        return split_keys(data.decode("utf-8", "replace"))


def status_line(t: float, hand, seen, predictor) -> str:
    """``t=... hand=(x,y,z) seen=(x,y,z) m task=... p[...] T=...`` for the terminal.

    ``hand`` is the true hand position (m), ``seen`` the tracker's measurement the
    policy received (m), then the predictor's task, posterior and duration estimate.
    """
    post = predictor.task_posterior
    probs = " ".join(f"{k}={v:.2f}" for k, v in post.items())
    x, y, z = (float(v) for v in hand)
    a, b, c = (float(v) for v in seen)
    return (f"t={t:5.2f}s hand=({x:+.3f},{y:+.3f},{z:+.3f}) seen=({a:+.3f},{b:+.3f},{c:+.3f}) "
            f"m task={predictor.task} p[{probs}] T={predictor.duration:.2f}s")


def _outcome(info: dict, t: float) -> str:
    if info.get("is_success"):
        return f"handover at {info['handover_time']:.2f} s"
    return f"no handover by {t:.2f} s (time limit)"


def run_teleop(env, policy, keyboard: Keyboard, *, seed: int = 0, running: bool = False,
               out: Callable[[str], None] = print) -> int:
    """The teleop loop; returns the number of episodes played.

    Parameters
    ----------
    env : gymnasium.Env
        A handover environment made with ``render_mode="human"`` (its viewer is used).
    policy : IProMPPolicy
        Drives the robot; its predictor's overlays are drawn in the viewer.
    keyboard : Keyboard
        Where keys come from.
    seed : int
        Seed of the first episode (then seed + 1, ...).
    running : bool
        Start the clock at once (default: press space).
    out : callable
        Prints a line.

    The loop ends on ``q``, or when the input is closed and the episode is over.
    """
    state = TeleopState(running=running)
    episodes, over = 1, False

    def new_episode(k: int):
        obs, _ = env.reset(seed=seed + k, options={"source": "teleop"})
        policy.reset()
        state.direction[:] = 0.0
        out(f"episode {k + 1}: the hand is at the start; "
            + ("the clock runs" if state.running else "press space to start the clock"))
        return obs

    obs = new_episode(0)
    viewer = env.unwrapped.viewer
    overlay = viewer.add_overlay(policy.predictor.model.tasks, rng=np.random.default_rng(seed))
    out("keys:\n" + HELP_TEXT)
    n_updates, frame = 0, -1
    while True:
        for key in keyboard.read(0.0 if state.running and not over else 0.05):
            action = state.apply(key)
            if action == "quit":
                return episodes
            if action == "help":
                out("keys:\n" + HELP_TEXT)
            elif action == "reset":
                obs, over, n_updates, frame = new_episode(episodes), False, 0, -1
                episodes += 1
            elif action == "move":
                v = state.velocity
                out(f"> {key}: hand velocity ({v[0]:+.2f}, {v[1]:+.2f}, {v[2]:+.2f}) m/s")
            elif action == "clock":
                viewer.restart_pacing()  # real time resumes from here, not from the reset
                out("> clock " + ("runs" if state.running else "stopped"))
        if keyboard.closed and not state.running and not over:
            state.running = True  # no more keys: play the episode out
            viewer.restart_pacing()
        if over and keyboard.closed:
            return episodes
        if not state.running or over:
            continue
        env.unwrapped.motion.set_velocity(state.velocity)
        obs, _, terminated, truncated, info = env.step(policy(obs))
        t = float(obs["time"][0])
        if int(round(t * viewer.scene.timeline.fps)) != frame:
            frame = int(round(t * viewer.scene.timeline.fps))
            overlay.show(policy.predictor, t, executed_q=obs["q"])
        if len(policy.predictor.updates) > n_updates:
            n_updates = len(policy.predictor.updates)
            out(status_line(t, env.unwrapped.motion.position(t), obs["hand"], policy.predictor))
        if terminated or truncated:
            over = True
            out(f"episode over: {_outcome(info, t)}, gripper {100 * info['distance']:.1f} cm "
                f"from the object, task {policy.task}; n: new episode, q: quit")
