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

    Every observation's arrays are new (nothing is shared with the environment or with
    another observation); ``hand``, ``object``, ``q`` and ``dq`` are slices of one new
    array, clipped to the space in one go (the observation is built at every step).
    """

    def __init__(self, space: spaces.Dict, observe_body: bool) -> None:
        self.space, self.observe_body = space, observe_body
        #: Each Box entry's bounds, looked up once.
        self._bounds = {k: (v.low, v.high) for k, v in space.items()
                        if isinstance(v, spaces.Box)}
        vector = ("hand", "object", "q", "dq")
        self._low = np.concatenate([self._bounds[k][0] for k in vector])
        self._high = np.concatenate([self._bounds[k][1] for k in vector])
        ends = np.cumsum([self._bounds[k][0].size for k in vector]).tolist()
        self._slices = list(zip(vector, [slice(a, b) for a, b in zip([0, *ends], ends)]))
        self._scalars = {k: (float(low[0]), float(high[0])) for k, (low, high)
                         in self._bounds.items() if low.shape == (1,)}
        self._body_keys = [(name, f"{name}_valid") for name in BODY_DIMS]
        self.reset()

    def reset(self) -> None:
        """A new episode: its first observation's hand frame is new."""
        self._given: float | None = None

    def __call__(self, motion: Any, t: float, grasp: Sequence[float], q: list[float],
                 dq: list[float], opening: float) -> dict[str, np.ndarray]:
        """The observation at episode time ``t`` (s) of ``motion`` (its ``tracked(t)``:
        :meth:`sandbox.envs.human.HumanMotion.tracked`) and the robot's state: the grasp
        point (3 floats, m), joint positions ``q`` and velocities ``dq`` (lists of dof
        floats, rad, rad/s) and the gripper's opening in [0, 1]."""
        hand, frame, body = motion.tracked(t)
        # np.clip's result without its wrapper's cost (NaN stays NaN), every entry at once
        values = np.minimum(np.maximum(np.array([*hand.tolist(), *grasp, *q, *dq]),
                                       self._low), self._high)
        obs = {key: values[at] for key, at in self._slices}
        (g_low, g_high), (t_low, t_high) = self._scalars["gripper"], self._scalars["time"]
        # an entry of one value in Python floats (max(x, low) keeps a NaN x, as np.maximum)
        obs["gripper"] = np.array([min(max(float(opening), g_low), g_high)])
        obs["time"] = np.array([min(max(float(t), t_low), t_high)])
        if not self.observe_body:
            return obs
        obs.update(self._hand_frame(float(frame), t))
        self._body(body, obs)
        return obs

    def _hand_frame(self, frame: float, t: float) -> dict[str, np.ndarray]:
        """``hand_valid`` (1 for a frame not given before) and ``hand_time`` (the frame's
        time, s; a frame shown before its time, the motion's first valid one, at ``t``)."""
        new = frame != self._given
        self._given = frame
        return {"hand_valid": np.array([new], dtype=np.int8),
                "hand_time": np.array([min(max(min(frame, float(t)), 0.0), TIME_MAX)])}

    def _body(self, body: dict[str, np.ndarray | None], out: dict[str, np.ndarray]) -> None:
        """Add ``arm``/``emg`` (0 where unmeasured: None or left out of ``body``, the
        motion's ``tracked`` body samples) and their ``*_valid`` flags (int8 (1,)) to
        ``out``."""
        for name, flag in self._body_keys:
            value = body.get(name)
            if value is not None:
                low, high = self._bounds[name]
                out[name] = np.minimum(np.maximum(value, low), high)
            else:
                out[name] = np.zeros(BODY_DIMS[name])
            out[flag] = np.array([value is not None], dtype=np.int8)
