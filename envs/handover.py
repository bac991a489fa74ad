"""The Baxter handover environment: simulation + robot + human + task."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from sandbox import urdf
from sandbox.envs.arguments import (  # noqa: F401 - VIEWER_KEYS re-exported
    VIEWER_KEYS,
    check_control_hz,
    check_reward_weights,
    check_substeps,
    check_viewer_options,
)
from sandbox.envs.human import HumanHand, HumanMotion
from sandbox.envs.observations import Observer, observation_space
from sandbox.envs.options import EpisodeOptions, parse_options
from sandbox.envs.pybullet import Simulation
from sandbox.envs.robot import RobotArm
from sandbox.envs.sources import FAMILIES, episode_motion
from sandbox.envs.task import HandoverTask, RewardWeights, object_for
from sandbox.robot.arms import arm_spec
from sandbox.validation import check_array, check_positive

FloatArray = NDArray[np.float64]
#: Physics steps run before the initial state is saved (lets the parked objects settle).
SETTLE_STEPS = 100


class ClosedEnvironmentError(gym.error.ClosedEnvironmentError, RuntimeError):
    """``reset``, ``step`` or ``render`` after :meth:`close`: both Gymnasium's
    :class:`gymnasium.error.ClosedEnvironmentError` and a :class:`RuntimeError`."""


class BaxterHandoverEnv(gym.Env):
    """A human hands an object to the robot (Baxter's left arm by default), which must meet
    the hand and take it.

    Description
    -----------
    A simulated Rethink Baxter (PyBullet, ``example-robot-data``; or a Panda, UR5 or
    Kinova, ``robot=``) stands at the origin of its ``base`` frame facing +x; a human 1.4 m
    in front of it reaches toward it with an object in the left hand. The hand is
    kinematic: it replays a synthetic reach (seeded, family ``"objects"``: box,
    glasses case, tape; or ``"diverging"``: left, right, up, down, straight,
    sharing their start), a recorded trial or a scripted motion, or it follows a
    teleoperator (:class:`~sandbox.envs.teleop.TeleopMotion`). The robot sees the hand through
    the skeleton tracker (30 Hz frames, jumps). When the gripper closes within
    ``grasp_radius`` of the object's grasp point, the object is fixed to the
    gripper and the hand lets go: the handover succeeds. The policy (e.g.
    :class:`sandbox.episodes.policies.IProMPPolicy`) lives outside the environment.

    Action space
    ------------
    ``Box(d + 1,)`` float64: the arm's d joint position targets (rad, bounds =
    joint limits; clipped to them; Baxter: seven, ``left_s0 ... left_w2``), then
    a gripper command in [-1, 1] (> 0 closes, <= 0 opens). The motors track
    the targets within the URDF's effort and speed limits. ``robot=`` chooses
    the arm (:mod:`sandbox.robot.arms`: baxter, panda, ur5, kinova; dof 7, 7, 6, 6).

    Observation space
    -----------------
    ``Dict``, float64 entries (the ``*_valid`` flags int8), Baxter's base frame:

    ==============  =====  =======================================================
    key             shape  meaning
    ==============  =====  =======================================================
    ``hand``        (3,)   latest tracker measurement of the human hand (m)
    ``hand_valid``  (1,)   1 if ``hand`` is a tracker frame not observed
                           before, 0 if the tracker has sent no new frame since
                           the last step (its frames are slower than the
                           steps: 30 Hz); ``hand`` then holds the last frame (v1)
    ``hand_time``   (1,)   time (s, episode clock) of the frame in ``hand``:
                           the tracker sample's own time, not the step's (v1)
    ``arm``         (6,)   latest tracker measurement of the same-side elbow,
                           then shoulder, x/y/z each (m); 0 where ``arm_valid``
                           is 0 (v1)
    ``arm_valid``   (1,)   1 if ``arm`` holds a measurement, 0 if the tracker
                           has not seen the arm yet or the source has no arm:
                           teleop, scripted motions, synthetic motions without
                           an ``arm`` modality (v1)
    ``emg``         (8,)   latest EMG envelope of a recorded replay (8 Myo
                           channels, rectified and low-pass filtered, raw
                           units, 0 .. ``EMG_MAX`` of
                           :mod:`~sandbox.envs.observations`); 0 where
                           ``emg_valid`` is 0 (v1)
    ``emg_valid``   (1,)   1 if ``emg`` holds a measurement: recorded trials
                           with EMG only, it is not simulated (v1)
    ``object``      (3,)   the object's grasp point (m)
    ``q``           (d,)   arm joint positions (rad), d joints (Baxter 7)
    ``dq``          (d,)   arm joint velocities (rad/s)
    ``gripper``     (1,)   finger opening, 0 closed .. 1 open
    ``time``        (1,)   time since the episode started (s)
    ==============  =====  =======================================================

    A missing measurement is a held or 0 value with its ``*_valid`` flag 0, not
    NaN: Gymnasium's checker rejects NaN (a NaN is outside any ``Box`` and
    breaks its determinism checks). :func:`sandbox.episodes.policies.modality_values`
    turns the pair back into NaN for a predictor, which skips a row without a
    new hand frame and marginalises a missing arm or EMG; the policy stamps the
    row with ``hand_time``.
    Recorded replays carry the arm and EMG preprocessed as the evaluation's
    test streams (``preprocess="causal"``: only accepted tracker frames);
    the value is held from the latest accepted frame, as for ``hand``.

    Rewards
    -------
    ``reward_distance + reward_success + reward_action_rate`` (each in
    ``info``): minus the fingertip-to-grasp-point distance (m, weight 1),
    +10 at the handover, minus 0.01 x the sum of squared joint-target rates
    ((rad/s)^2). Weights: :class:`sandbox.envs.task.RewardWeights`.

    Starting state
    --------------
    The arm at the recorded home configuration, gripper open, the hand at the motion's first
    sample holding the object. Reset restores a saved simulator state (nothing is reloaded).

    Episode end
    -----------
    Terminated at the handover (``info["is_success"]``); truncated by the time limit
    (``max_episode_steps=300``, 6 s at 50 Hz, when made with ``gym.make``). After its last
    sample the hand holds still.

    Arguments
    ---------
    ``gym.make("sandbox/BaxterHandover-v1", ...)`` after ``import sandbox.envs``
    (or ``gym.make("sandbox.envs:sandbox/BaxterHandover-v1")``) with

    * ``family`` ("objects" or "diverging"): synthetic tasks (set by the id);
    * ``robot`` ("baxter"; "panda", "ur5", "kinova"): the arm, at its world pose;
    * ``observe_body`` (True; False for the v0 ids): observe the arm and EMG
      (``arm``, ``arm_valid``, ``emg``, ``emg_valid``);
    * ``render_mode`` (None, "human" or "rgb_array"): "human" shows the
      episode live in the browser (meshcat, see Rendering);
    * ``control_hz`` (50, in [1, 1000], :data:`sandbox.limits.BOUNDS`): steps per second;
      ``substeps`` (5, an integer from 1 to :data:`~sandbox.envs.arguments.MAX_SUBSTEPS`): physics
      steps per control step (physics at 250 Hz);
    * ``grasp_radius`` (0.05 m); ``reward_weights`` (a :class:`RewardWeights`, or a dict of
      its fields, e.g. ``{"success": 5.0}``);
    * ``default_object`` ("box"): object of tasks without one (diverging tasks);
    * ``viewer_options`` (dict): arguments of :class:`sandbox.viz.Viewer` in
      "human" mode (default ``{"realtime": True}``; e.g. ``open_browser=True``,
      ``host="0.0.0.0"`` to serve the viewer beyond this machine).

    Every argument is checked when the environment is made: a wrong type or value is a
    ``ValueError`` naming it. ``reset``, ``step`` and ``render`` after :meth:`close` raise
    :class:`ClosedEnvironmentError` (a ``RuntimeError``).

    ``reset(seed=..., options=...)`` options (all optional, validated):
    ``task``; ``object`` (box, glasses_case, tape, measuring_tape, screwdriver;
    default from the task: pencil_box -> box, gummed_paper -> tape,
    measurement_tape -> measuring_tape, screw_driver -> screwdriver);
    ``source``      ("synthetic" or a folder ``<root>/<task>/<trial>.csv``);
    ``trial``       (recorded: index or file name); ``speed`` (human speed factor,
    0.25-4); ``switch_to``, ``switch_phase`` (synthetic intent switch); ``session`` (its seed);
    ``source="teleop"``: the hand follows velocity commands given to ``env.unwrapped.motion``
    (a :class:`~sandbox.envs.teleop.TeleopMotion`);
    ``motion``: a scripted :class:`~sandbox.envs.human.HumanMotion` (e.g. from
    :func:`~sandbox.envs.sources.waypoint_motion`); ``grasp_offset``: where the
    object's grasp point rides from the tracked hand (3,) m, or one per task
    (``{task: offset}``, e.g. ``MeetingGeometry.offsets()`` of the model's learned
    meeting geometry, :mod:`sandbox.data.geometry`); default
    :data:`~sandbox.envs.task.DEFAULT_HOLD_OFFSET`. ``info["grasp_offset"]`` says
    which was used.

    Rendering
    ---------
    ``"rgb_array"``: :meth:`render` returns a PyBullet camera image.
    ``"human"``: the first ``reset`` starts a meshcat server on localhost (no display
    needed) and prints its URL; every ``reset`` and ``step`` then shows the scene in the
    browser, paced to real time, and records it (``env.unwrapped.viewer.save_html(path)``
    writes the episode's replay; a policy's predictions can be drawn with
    ``viewer.add_overlay``). The server stops with :meth:`close`, and at the latest when
    this process ends.

    Version history
    ---------------
    * v1: the observation gains ``arm``, ``arm_valid``, ``emg`` and
      ``emg_valid``; recorded replays carry the arm and EMG, synthetic
      motions the arm when generated with it. Later (issue 16), without a new
      id: ``hand_valid`` and ``hand_time``, the tracker frame's own time and
      whether it is new; (issue 21) the ``grasp_offset`` and ``session`` options, and info.
    * v0: initial version; ``render_mode="human"``, the ``teleop`` source and
      the ``motion`` option added without changing any other behaviour. Kept
      registered (``observe_body=False``) for one release.

    Attributes
    ----------
    sim : Simulation
        The PyBullet world; ``sim.client`` and ``sim.bodies`` let a viewer mirror it.
    robot : RobotArm
    human : HumanHand
    task : HandoverTask
    motion : HumanMotion or TeleopMotion or None
        The current episode's hand motion.
    viewer : sandbox.viz.Viewer or None
        The live viewer of ``render_mode="human"`` (made at the first reset).
    """

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 50}

    def __init__(self, family: str = "objects", render_mode: str | None = None, *,
                 control_hz: float = 50.0, substeps: int = 5, grasp_radius: float = 0.05,
                 reward_weights: RewardWeights | None = None,
                 default_object: str = "box", viewer_options: Mapping | None = None,
                 observe_body: bool = True, robot: str = "baxter") -> None:
        arm_spec(robot)                                   # unknown name: one-line ValueError
        if not isinstance(observe_body, bool):
            raise ValueError(f"observe_body: expected True or False, got {observe_body!r}")
        self.observe_body = observe_body
        if not isinstance(family, str) or family not in FAMILIES:
            raise ValueError(f"family: expected one of {list(FAMILIES)}, got {family!r}")
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ValueError(f"render_mode: expected None, 'human' or 'rgb_array', "
                             f"got {render_mode!r}")
        self.viewer_options = {"realtime": True, **check_viewer_options(viewer_options)}
        self.viewer = None
        self._closed = False
        if not isinstance(default_object, str) or default_object not in urdf.OBJECTS:
            raise ValueError(f"default_object: expected one of {list(urdf.OBJECTS)}, "
                             f"got {default_object!r}")
        self.family, self.render_mode, self.default_object = family, render_mode, default_object
        self.dt = 1.0 / check_control_hz(control_hz)
        self.substeps = check_substeps(substeps)
        self.metadata = {**self.metadata, "render_fps": int(round(control_hz))}
        weights = check_reward_weights(reward_weights)
        check_positive(grasp_radius, "grasp_radius")
        self.sim = Simulation(physics_hz=control_hz * self.substeps)
        self.robot = RobotArm(self.sim, robot)
        self.human = HumanHand(self.sim)
        self.task = HandoverTask(self.sim, self.robot, self.human, grasp_radius=grasp_radius,
                                 weights=weights)
        self._settle_and_save()
        self.action_space = spaces.Box(np.append(self.robot.lower, -1.0),
                                       np.append(self.robot.upper, 1.0), dtype=np.float64)
        self.observation_space = observation_space(self.robot, observe_body)
        self._observer = Observer(self.observation_space, observe_body)
        self.motion: HumanMotion | None = None
        self.episode: EpisodeOptions | None = None

    # ------------------------------------------------------------------ setup
    def _settle_and_save(self) -> None:
        self.robot.reset()
        for _ in range(SETTLE_STEPS):
            self.sim.step_physics()
        self.sim.save()

    # ------------------------------------------------------------------ API
    def reset(self, *, seed: int | None = None,
              options: Mapping[str, Any] | None = None) -> tuple[dict, dict]:
        """Start an episode: Gymnasium's ``reset``; the options are listed under Arguments."""
        self._check_open("reset")
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer))
                                 or seed < 0):
            raise ValueError(f"seed: expected None or an integer >= 0, got {seed!r}")
        super().reset(seed=None if seed is None else int(seed))
        episode = parse_options(options, self.family)
        motion = episode_motion(episode, self.family, self.np_random)
        object_name = episode.object or object_for(motion.task, self.default_object)
        hold_offset = episode.hold_offset(motion.task)
        self.task.release()
        self.sim.restore()
        self.robot.reset()
        self.task.reset(object_name, motion.position(0.0), hold_offset)
        self.motion, self.episode = motion, episode
        self._observer.reset()
        self._steps, self._t, self._prev_target = 0, 0.0, np.array(self.robot.spec.q_home)
        self._handover_time: float | None = None
        info = {"task": motion.task, "object": object_name, "source": motion.source,
                "speed": episode.speed, "duration": motion.duration,
                "grasp_offset": self.task.hold_offset.tolist()}
        if self.render_mode == "human":
            self._show(new_episode=True)
        return self._observation(), info

    def step(self, action) -> tuple[dict, float, bool, bool, dict]:
        """One control step (Gymnasium's ``step``); the reward's terms are in ``info``."""
        self._check_open("step")
        if self.motion is None:
            raise RuntimeError("step: call reset() before step()")
        robot, dof = self.robot, self.robot.dof      # a finite a.a: finite a (else check_array)
        if not (type(action) is np.ndarray and action.dtype == np.float64
                and action.shape == (dof + 1,) and math.isfinite(action.dot(action))):
            action = check_array(action, "action", 1, shape=(dof + 1,))  # else read, not kept
        target = np.minimum(np.maximum(action[:dof], robot.lower), robot.upper)
        robot.command(target.tolist(), close=bool(action[dof] > 0.0))
        physics_dt = self.dt / self.substeps
        self.task.advance(self.motion.positions([self._t + k * physics_dt
                                                 for k in range(1, self.substeps + 1)]))
        self._steps += 1
        self._t = self._steps * self.dt
        q, dq, opening = robot.read()     # read once: the handover, reward and observation
        grasp = self.task.grasp_floats()
        distance = self.task.distance(grasp)
        handed = self.task.try_handover(opening, distance)   # fixes the object where it is
        self._handover_time = self._t if handed else self._handover_time
        terms = self.task.reward_terms(distance, handed, (target - self._prev_target) / self.dt)
        self._prev_target = target
        reward = float(sum(terms.values()))
        info = {**terms, "distance": distance, "is_success": self.task.handed_over,
                "handover_time": self._handover_time, "time": self._t,
                "task": self.motion.task, "object": self.task.object}
        if self.render_mode == "human":
            self._show()
        return self._observation((q, dq, opening, grasp)), reward, handed, False, info

    def render(self) -> NDArray[np.uint8] | None:
        """RGB image (360, 480, 3) of the scene in ``"rgb_array"`` mode; None otherwise.

        In ``"human"`` mode the scene is shown in the browser (also done by every
        ``reset`` and ``step``) and None is returned.
        """
        if self.render_mode is not None:
            self._check_open("render")
        if self.render_mode == "human":
            if self.motion is None:
                raise RuntimeError("render: call reset() before render()")
            self._show()
            return None
        if self.render_mode != "rgb_array":
            return None
        return self.sim.render()

    def close(self) -> None:
        """Stop the live viewer's server, disconnect the simulator (safe to call twice)."""
        if self.viewer is not None:
            self.viewer.close()
        self.sim.close()
        self._closed = True

    def _check_open(self, call: str) -> None:
        if self._closed:
            raise ClosedEnvironmentError(f"{call}: the environment is closed; make a new one "
                                         "with gym.make(...)")

    def _show(self, new_episode: bool = False) -> None:
        """Send the scene at the current time to the live viewer (made on first use)."""
        if self.viewer is None:
            from sandbox.viz import Viewer

            self.viewer = Viewer(live=True, **self.viewer_options)
            self.viewer.add_simulation(self.sim)
            self.viewer.add_tracked_arm(self.tracked_arm)
        elif new_episode:
            self.viewer.restart_recording()
            if self.viewer.overlay is not None:
                self.viewer.overlay.reset()
        self.viewer.update(self._t, force=new_episode)

    # ------------------------------------------------------------- internals
    def _observation(self, read: tuple | None = None) -> dict[str, FloatArray]:
        """The observation now; ``read``: ``(q, dq, opening, grasp)`` if read already (the
        robot's ``read()`` and the task's ``grasp_floats()``)."""
        q, dq, opening, grasp = read or (*self.robot.read(), self.task.grasp_floats())
        return self._observer(self.motion, self._t, grasp, q, dq, opening)

    def human_intent(self, t: float | None = None) -> str | None:
        """The task the human pursues at time ``t`` (s; default now), when the source knows it.

        A synthetic motion: its task, before and after an intent switch
        (``switch_to``; the switch time follows the ``speed`` option); a recorded
        trial: its task. ``None`` for the teleoperated hand and scripted motions
        (the ``motion`` option), whose intent is not known. Feeds the viewer's
        panel (``overlay.show(..., truth=env.unwrapped.human_intent())``).
        """
        if self.motion is None:
            raise RuntimeError("human_intent: call reset() first")
        if self.episode.motion is not None or self.episode.source == "teleop":
            return None
        intent = self.motion.meta.get("intent")
        if intent is None:
            return str(self.motion.task)
        t = self._t if t is None else float(t)
        return str(intent.task_at(t * float(self.motion.meta.get("speed", 1.0))))

    def tracked_arm(self) -> tuple[FloatArray, FloatArray]:
        """What the tracker measures now: hand (3,) and arm (6,: elbow, shoulder) m, NaN if not.

        Feeds the viewer's tracked arm (:meth:`sandbox.viz.Viewer.add_tracked_arm`).
        """
        if self.motion is None:
            raise RuntimeError("tracked_arm: call reset() first")
        return self.motion.measurement(self._t), self.motion.body_measurement("arm", self._t)

    @property
    def bullet_client(self):
        """The PyBullet client (for viewers mirroring the scene)."""
        return self.sim.client

    @property
    def body_ids(self) -> dict[str, int]:
        """Body name -> PyBullet body id (``baxter``, ``human_hand``, objects, ``table``...)."""
        return dict(self.sim.bodies)
