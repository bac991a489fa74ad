"""Policies for the handover environments: the Interaction ProMP predictor as a controller.

A policy maps each observation of :mod:`sandbox.envs` (a dict with ``hand``,
``arm``, ``emg``, ``object``, ``q``, ``time``...) to an action (dof + 1,): the
arm's joint targets (rad; Baxter's seven) and a gripper command. ``robot=``
names the arm; another than Baxter follows the plan retargeted
(:mod:`sandbox.episodes.steering`). :class:`IProMPPolicy` feeds the
observed modalities (every one its model has and the environments carry:
``hand``, ``arm``, ``emg``, see :func:`modality_values`) to a
:class:`~sandbox.core.DynamicPredictor` and steers the arm along the blended
plan; :class:`StaticPolicy` does the same with the static baseline
(:class:`~sandbox.core.StaticPredictor`, one prediction after a fraction of
the motion; :class:`~sandbox.episodes.method_policy.MethodPolicy` does it with
BIP, eBIP, DTW or nearest-neighbour). :class:`RecordedRobotPolicy` replays what
the real robot did in a recorded trial: the ceiling a predictor of the recorded robot can reach in a
replay of that trial. A modality missing at a step (NaN, e.g. no EMG in a synthetic
episode) is marginalised by the predictor, not zero-filled.

From the plan to an action, at control period ``dt``:

* the target is the plan's mean at the next control time ``t + dt``;
* it moves from the previous target by at most ``max_velocity * dt`` per
  joint (Baxter's URDF speed limits), so targets are always reachable;
* the gripper closes when the fingertip (forward kinematics of the observed
  joints) is within ``close_radius`` of the object, and stays open otherwise.

The predictor expects about 20 observations per second (the paper keeps one
of every 5 samples at ~100 Hz): the policy keeps one of every
``round(control_hz / 20)`` observations with a new tracker frame (2 at 50 Hz:
15 per second of the tracker's 30 Hz frames). Each observation is fed as the
tracker gave it (:func:`tracker_row`): stamped with the frame's own time
(``hand_time``), NaN at a step without a new frame (``hand_valid`` 0), which the
predictor skips.

:func:`fit_family_model` fits the model on seeded synthetic demonstrations of
an environment's family, cached in-process.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import NDArray

from sandbox.core import DynamicPredictor, IProMP, StaticPredictor
from sandbox.episodes.policy import Beliefs, check_joint_model
from sandbox.episodes.steering import Steering
from sandbox.validation import check_array

FloatArray = NDArray[np.float64]

#: Observations per second the predictor is designed for.
PREDICTOR_HZ = 20.0
#: Predictor options a closed-loop policy changes from their defaults: the episode ends
#: at the handover, so there is no after-motion to ignore, and holding the task once the
#: motion seems over commits to a wrong one when the human is slower than predicted
#: (diverging scenario, 20 episodes, seed 0: success 0.75 with the hold, 0.95 without).
CLOSED_LOOP = {"until_end": False}
#: Modalities the environments' observations carry (v1; the v0 ids carry the hand only).
ENV_MODALITIES = ("hand", "arm", "emg")
#: Dims of each of :data:`ENV_MODALITIES`.
MODALITY_DIMS = {"hand": 3, "arm": 6, "emg": 8}


def modality_values(obs: Mapping[str, FloatArray], names, *,
                    required: bool = True) -> dict[str, FloatArray]:
    """The observed modalities ``names`` of an environment observation, NaN where unmeasured.

    Parameters
    ----------
    obs : mapping
        An observation of :mod:`sandbox.envs`: ``hand`` (3,) m and, in v1,
        ``arm`` (6,) m and ``emg`` (8,) with their ``arm_valid``/``emg_valid``
        flags (1,).
    names : sequence of str
        Modalities among :data:`ENV_MODALITIES`.
    required : bool
        If True a name missing from ``obs`` is a ``ValueError``; if False it is
        left out of the result (unobserved).

    Returns
    -------
    dict
        Name -> copy of its values (dims,); all NaN where the ``*_valid`` flag is 0.
        ``obs`` is not changed.
    """
    out = {}
    for name in names:
        if name not in MODALITY_DIMS:
            raise ValueError(f"names: expected modalities among {list(ENV_MODALITIES)}, "
                             f"got {name!r}")
        if name not in obs:
            if required:
                raise ValueError(f"obs: expected a {name!r} entry (a -v1 environment "
                                 f"observes hand, arm and emg), got keys {sorted(obs)}")
            continue
        values = check_array(obs[name], f"obs[{name!r}]", 1, shape=(MODALITY_DIMS[name],),
                             allow_nan=True)
        flag = obs.get(f"{name}_valid")
        if flag is not None and not np.asarray(flag).all():
            values = np.full(values.shape, np.nan)
        out[name] = values
    return out


def tracker_row(obs: Mapping[str, FloatArray], names, *,
                required: bool = True) -> tuple[float, dict[str, FloatArray]]:
    """What a tracker stream gives for an observation: the sample's time (s) and values.

    The time is ``obs["hand_time"]``, the tracker frame's own time (the step's
    ``time`` for an observation without it, the v0 ids). Where ``hand_valid`` is 0
    the tracker has sent no new frame since the last step: every modality is NaN
    (the arm and the replayed EMG come with the hand's frames), so the predictor
    skips the row instead of taking a stale sample as new. Otherwise the values are
    :func:`modality_values` (``names``, ``required``).
    """
    stamp = obs.get("hand_time", obs["time"])
    t = float(np.asarray(stamp, dtype=float).reshape(-1)[0])
    values = modality_values(obs, names, required=required)
    flag = obs.get("hand_valid")
    if flag is not None and not np.asarray(flag).all():
        values = {name: np.full(v.shape, np.nan) for name, v in values.items()}
    return t, values


def fit_family_model(family: str = "diverging", n_per_task: int = 20, seed: int = 0,
                     n_basis: int | None = None, observe=("hand",), *,
                     calibrated: bool = False, shrinkage: str = "none") -> IProMP:
    """An IProMP fitted on synthetic demonstrations of ``family`` (cached per arguments).

    Parameters
    ----------
    family : str
        A synthetic dataset name (``"diverging"``, ``"objects"``, ``"two_task"``):
        the environment's family.
    n_per_task : int
        Demonstrations per task.
    seed : int
        Seed of the demonstrations.
    n_basis : int, optional
        Basis functions per dim; default :class:`~sandbox.core.IProMP`'s (all other
        settings but ``shrinkage`` are its defaults too).
    observe : sequence of str or str
        Modalities of the demonstrations: ``"hand"`` (default) or ``"hand,arm"``
        (the synthetic human arm; EMG is not simulated).
    calibrated : bool
        Also calibrate its familiarity (:func:`~sandbox.episodes.sessions.calibrated_synthetic`).
    shrinkage : {"none", "auto"}
        :class:`~sandbox.core.IProMP`'s option.

    Returns
    -------
    IProMP
        Shared by every caller with the same arguments (do not modify it), with the
        demonstrations' meeting geometry (:mod:`sandbox.data.geometry`).
    """
    names = [n.strip() for n in observe.split(",")] if isinstance(observe, str) else observe
    from sandbox.episodes.sessions import calibrated_synthetic, fit_synthetic

    fit = calibrated_synthetic if calibrated else fit_synthetic
    more = {} if shrinkage == "none" else {"shrinkage": shrinkage}   # one cache key per model
    return fit(family, n_per_task, seed, n_basis, tuple(names), **more)


class IProMPPolicy(Steering):
    """Dynamic Interaction ProMP controller: re-predict every ``dow_t`` seconds, follow the plan.

    Parameters
    ----------
    model : IProMP
        A fitted model (robot dims: the 7 left-arm joints) with some of the
        modalities the environments observe (:data:`ENV_MODALITIES`); others
        it has are marginalised.
    observe : sequence of str or str, optional
        Modalities to feed (e.g. ``["hand"]`` or ``"hand,arm,emg"``); each must
        be the model's and in every observation. Default: every modality of the
        model among :data:`ENV_MODALITIES` that the observation carries.
    dow_t : float
        Dynamic observation window (s).
    control_hz : float
        The environment's control rate (Hz); sets the step and the subsampling.
    close_radius : float
        Fingertip-to-object distance (m) under which the gripper closes.
    max_velocity : array_like, shape (dof,), optional
        Joint speed limits (rad/s) of the arm; default its URDF's ``<limit velocity>``
        (Baxter's: :func:`sandbox.robot.joint_speed_limits`).
    robot : str
        The arm acting (:data:`sandbox.robot.arms.ROBOTS`, default ``"baxter"``); any
        other arm, or a model fitted in task space, is retargeted
        (:mod:`sandbox.episodes.steering`).
    **options
        More options of the predictor (``blend_rate``, ``likelihood``...);
        ``until_end`` defaults to False here (:data:`CLOSED_LOOP`).

    Attributes
    ----------
    predictor : DynamicPredictor
        Internal: runners read :attr:`beliefs`.
    beliefs : Beliefs
        What the predictor believes now (read-only).
    history : list of (float, str)
        The recognised task after each observation: ``(time, task)`` (``""`` before the
        predictor's first update).

    Examples
    --------
    >>> import gymnasium as gym, sandbox.envs
    >>> env = gym.make("sandbox/BaxterHandoverDiverging-v1")
    >>> policy = IProMPPolicy(fit_family_model("diverging"), dow_t=0.2)
    >>> obs, info = env.reset(seed=3)
    >>> done = False
    >>> while not done:
    ...     obs, reward, terminated, truncated, info = env.step(policy(obs))
    ...     done = terminated or truncated
    >>> info["is_success"]
    True
    >>> env.close()
    """

    def __init__(self, model: IProMP, *, dow_t: float = 0.2, control_hz: float = 50.0,
                 close_radius: float = 0.045, max_velocity=None, observe=None,
                 robot: str = "baxter", **options) -> None:
        self._setup(model, observe, control_hz, close_radius, max_velocity, robot)
        self.predictor: DynamicPredictor | StaticPredictor = DynamicPredictor(
            model, dow_t=dow_t, subsample=self.subsample, observe=self.observe,
            **{**CLOSED_LOOP, **options})
        self.reset()

    def _setup(self, model, observe, control_hz: float, close_radius: float,
               max_velocity, robot: str = "baxter") -> None:
        check_joint_model(model)
        self.observe, self._required = _observed(model, observe)
        self._setup_steering(control_hz, close_radius, max_velocity, robot,
                             getattr(model, "robot_space", "joint") == "task")
        self.subsample = max(1, int(round(float(control_hz) / PREDICTOR_HZ)))

    def reset(self) -> None:
        """Forget the episode (called automatically when the observed time goes back)."""
        self.predictor.reset()
        self._target = None
        self._last_time = -np.inf
        self.history: list[tuple[float, str]] = []

    def __call__(self, obs: Mapping[str, FloatArray]) -> FloatArray:
        """The action (8,) for observation ``obs``: joint targets (rad), gripper command."""
        t = float(np.asarray(obs["time"]).reshape(-1)[0])
        if t < self._last_time:
            self.reset()
        self._last_time = t
        q = self._check_q(obs)
        self.predictor.observe(*tracker_row(obs, self.observe, required=self._required))
        self.history.append((t, self.task))
        mean, _ = self.predictor.command(t + self.dt)
        return self._act(q, mean, obs)

    @property
    def beliefs(self) -> Beliefs:
        """What the predictor believes now (:class:`~sandbox.episodes.policy.Beliefs`)."""
        return Beliefs.of_predictor(self.predictor)

    @property
    def task(self) -> str:
        """The task the predictor recognises now (``""`` before its first update, as
        :attr:`Beliefs.task <sandbox.episodes.policy.Beliefs>`)."""
        return self.predictor.task if self.predictor.updates else ""

    @property
    def task_posterior(self) -> dict[str, float]:
        """p(task | observations so far)."""
        return self.predictor.task_posterior


class StaticPolicy(IProMPPolicy):
    """The static baseline as a controller: predict once after observing ``ratio`` of the motion.

    Parameters
    ----------
    model : IProMP
        A fitted model.
    ratio : float
        Fraction of the expected (prior mean) duration observed before the one prediction.
    control_hz, close_radius, max_velocity, observe, **options
        As for :class:`IProMPPolicy`.
    """

    def __init__(self, model: IProMP, *, ratio: float = 0.3, control_hz: float = 50.0,
                 close_radius: float = 0.045, max_velocity=None, observe=None,
                 robot: str = "baxter", **options) -> None:
        self._setup(model, observe, control_hz, close_radius, max_velocity, robot)
        self.predictor = StaticPredictor(model, ratio=ratio, subsample=self.subsample,
                                         observe=self.observe, **{**CLOSED_LOOP, **options})
        self.reset()


def _observed(model: IProMP, observe) -> tuple[tuple[str, ...] | None, bool]:
    """The modalities a policy feeds, and whether the observations must carry them.

    Explicit ``observe`` (names or ``"a,b"``) must be among :data:`ENV_MODALITIES`
    (the predictor checks they are the model's); by default every modality of
    the model the environments observe, fed when the observation carries it.
    """
    if observe is None:
        if not getattr(model, "is_fitted", False):
            return None, False  # the predictor says it must be fitted
        names = tuple(m.name for m in model.modalities if m.name in ENV_MODALITIES)
        if not names:
            raise ValueError(f"model: expected a modality the environments observe "
                             f"{list(ENV_MODALITIES)}, got "
                             f"{[m.name for m in model.modalities]}")
        return names, False
    names = tuple(n.strip() for n in observe.split(",")) if isinstance(observe, str) \
        else tuple(observe)
    outside = [n for n in names if n not in ENV_MODALITIES]
    if outside or not names:
        raise ValueError(f"observe: expected modalities the environments observe "
                         f"{list(ENV_MODALITIES)}, got {list(names)}")
    return names, True


class RecordedRobotPolicy(Steering):
    """The recorded robot's own motion as a controller: the reference for recorded replays.

    Commands, at each step, the robot's recorded joint positions at the next
    control time (linear interpolation; the last recorded pose after the
    trial's end), through the same speed limit and gripper rule as
    :class:`IProMPPolicy`. In a replay of the same trial it shows how often the
    motion the predictors learn from would itself hand over in the simulated
    scene, where the object rides at the tracked hand.

    Parameters
    ----------
    times : array_like, shape (T,)
        The trial's sample times (s); the episode's time 0 is ``times[0]``.
    robot : array_like, shape (T, 7) or (T, 3)
        Recorded left-arm joint positions (rad), or with ``task_space`` positions (m).
    task : str
        The trial's task (reported as the recognised task).
    control_hz, close_radius, max_velocity
        As for :class:`IProMPPolicy`.
    arm : str
        The arm acting (``robot`` of :class:`IProMPPolicy`): another than Baxter follows
        the recorded fingertip path (retargeted).
    task_space : bool
        ``robot`` is a task-space position (m, world), followed through the arm's IK.
    """

    def __init__(self, times, robot, task: str, *, control_hz: float = 50.0,
                 close_radius: float = 0.045, max_velocity=None, arm: str = "baxter",
                 task_space: bool = False) -> None:
        from sandbox.validation import check_times

        t = check_times(times, "times")
        self._times = t - t[0]
        self._robot = check_array(robot, "robot", 2, shape=(t.size, 3 if task_space else 7))
        if not isinstance(task, str) or not task:
            raise ValueError(f"task: expected a task name, got {task!r}")
        self.task = task
        self._setup_steering(control_hz, close_radius, max_velocity, arm, task_space)
        self.reset()

    @classmethod
    def from_demo(cls, demo, **options) -> RecordedRobotPolicy:
        """The policy replaying a :class:`~sandbox.data.Demonstration`'s robot."""
        return cls(demo.times, demo.robot, demo.task,
                   task_space=getattr(demo, "robot_space", "joint") == "task", **options)

    def reset(self) -> None:
        """Start the trial again."""
        self._target = None

    @property
    def task_posterior(self) -> dict[str, float]:
        """Certain of the recorded task."""
        return {self.task: 1.0}

    @property
    def beliefs(self) -> Beliefs:
        """Certain of the recorded task; no predictor (no plan, no updates)."""
        return Beliefs(task=self.task, tasks=(self.task,), task_posterior={self.task: 1.0})

    def __call__(self, obs: Mapping[str, FloatArray]) -> FloatArray:
        """The action (8,): the recorded pose at ``t + dt`` (speed-limited), gripper command."""
        t = float(np.asarray(obs["time"]).reshape(-1)[0])
        q = self._check_q(obs)
        goal = np.array([np.interp(t + self.dt, self._times, joint) for joint in self._robot.T])
        return self._act(q, goal, obs)
