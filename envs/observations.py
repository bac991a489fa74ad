"""What the handover environment observes: its observation space and each observation.

The tracker delivers skeleton frames more slowly than the environment steps
(30 Hz frames, 50 Hz control): :class:`Observer` gives the hand of a frame
once, stamped with the frame's own time (``hand_time``); at a step where the
tracker has no new frame, ``hand`` holds the last frame and ``hand_valid`` is 0,
so a policy sees what a real tracker stream gives (a missing row) instead of a
stale sample stamped with the step time. See
:class:`~sandbox.envs.handover.BaxterHandoverEnv` for every entry.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from sandbox.envs.human import BODY_DIMS

FloatArray = NDArray[np.float64]
#: Upper bound of the observed EMG envelope (raw Myo units: hundreds in the recordings).
EMG_MAX = 1e4
#: Upper bound of the time entries (s).
TIME_MAX = 1e4
#: The order of an observation's entries.
_ORDER = ("hand", "object", "q", "dq", "gripper", "time", "hand_valid", "hand_time", "arm",
          "arm_valid", "emg", "emg_valid")


def observation_space(robot: Any, observe_body: bool) -> spaces.Dict:
    """The ``Dict`` space of :class:`~sandbox.envs.handover.BaxterHandoverEnv` (see there).

    ``robot`` gives the joint limits (``lower``, ``upper``, rad) and speed limits
    (``max_velocity``, rad/s); ``observe_body`` adds the v1 entries.
    """
    speed = 4.0 * robot.max_velocity
    return spaces.Dict({
        "hand": spaces.Box(-3.0, 3.0, (3,), np.float64),
        "object": spaces.Box(-3.0, 3.0, (3,), np.float64),
        "q": spaces.Box(robot.lower, robot.upper, dtype=np.float64),
        "dq": spaces.Box(-speed, speed, dtype=np.float64),
        "gripper": spaces.Box(0.0, 1.0, (1,), np.float64),
        "time": spaces.Box(0.0, TIME_MAX, (1,), np.float64),
        **(_v1_space() if observe_body else {}),
    })


def _v1_space() -> dict[str, spaces.Space]:
    return {"hand_valid": spaces.MultiBinary(1),
            "hand_time": spaces.Box(0.0, TIME_MAX, (1,), np.float64),
            "arm": spaces.Box(-3.0, 3.0, (BODY_DIMS["arm"],), np.float64),
            "arm_valid": spaces.MultiBinary(1),
            "emg": spaces.Box(0.0, EMG_MAX, (BODY_DIMS["emg"],), np.float64),
            "emg_valid": spaces.MultiBinary(1)}


class Observer:
    """Builds the observations of one environment; remembers the hand frame last given.

    Parameters
    ----------
    space : gymnasium.spaces.Dict
        The environment's observation space (values are clipped to it).
    observe_body : bool
        Add the v1 entries (``hand_valid``, ``hand_time``, ``arm``, ``emg`` and flags).

    Every observation is new: its float entries are slices of one new array, clipped to
    the space in one go, its flags slices of one new int8 array (it is built at every
    step); nothing is shared with the environment or with another observation.
    """

    def __init__(self, space: spaces.Dict, observe_body: bool) -> None:
        self.space, self.observe_body = space, observe_body
        floats = ["hand", "object", "q", "dq", "gripper", "time"]
        flags: list[str] = []
        if observe_body:
            floats += ["hand_time", *BODY_DIMS]
            flags = ["hand_valid", *(f"{name}_valid" for name in BODY_DIMS)]
        boxes = [space[k] for k in floats]
        self._low = np.concatenate([b.low for b in boxes])
        self._high = np.concatenate([b.high for b in boxes])
        ends = np.cumsum([b.low.size for b in boxes]).tolist()
        where = {k: (0, slice(a, b)) for k, a, b in zip(floats, [0, *ends], ends)}
        where.update({k: (1, slice(i, i + 1)) for i, k in enumerate(flags)})
        #: (key, 0 for the float array or 1 for the flags, slice), in the order of _ORDER
        self._layout = [(k, *where[k]) for k in _ORDER if k in where]
        if len(self._layout) != len(space.spaces):
            raise ValueError(f"space: expected the entries {list(where)}, got {list(space)}")
        self._zeros = {name: [0.0] * dims for name, dims in BODY_DIMS.items()}
        self.reset()

    def reset(self) -> None:
        """A new episode: its first observation's hand frame is new."""
        self._given: float | None = None

    def __call__(self, motion: Any, t: float, grasp: Sequence[float], q: list[float],
                 dq: list[float], opening: float) -> dict[str, np.ndarray]:
        """The observation at episode time ``t`` (s) of ``motion`` (its ``tracked(t)``:
        :meth:`sandbox.envs.human.HumanMotion.tracked`) and the robot's state: the grasp
        point (3 floats, m), joint positions ``q`` and velocities ``dq`` (lists of dof
        floats, rad, rad/s) and the gripper's opening in [0, 1].

        ``hand_valid`` is 1 for a frame not given before; ``hand_time`` is the frame's
        time (s; a frame shown before its time, the motion's first valid one, at ``t``);
        ``arm``/``emg`` are 0 where unmeasured, with their ``*_valid`` flag 0.
        """
        hand, frame, body = motion.tracked(t)
        t = float(t)
        values = [*hand.tolist(), *grasp, *q, *dq, float(opening), t]
        flags = []
        if self.observe_body:
            frame = float(frame)
            flags.append(frame != self._given)
            self._given = frame
            values.append(min(frame, t))
            for name, zeros in self._zeros.items():
                value = body.get(name)
                flags.append(value is not None)
                values.extend(zeros if value is None else value.tolist())
        # np.clip's result without its wrapper's cost (NaN stays NaN)
        arrays = (np.minimum(np.maximum(np.array(values), self._low), self._high),
                  np.array(flags, dtype=np.int8))
        return {key: arrays[which][at] for key, which, at in self._layout}
