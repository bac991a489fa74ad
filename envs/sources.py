"""Where an episode's hand motion comes from: the synthetic generator or a recorded trial.

* :func:`synthetic_motion`: one seeded reach of a task of a synthetic family
  (``"objects"``: box, glasses case, tape; ``"diverging"``: left, right, up,
  down, straight), optionally with an intent switch to another task. The body
  follows the clean reach, the robot observes it through the tracker model,
  and the same-side elbow and shoulder (``arm``) when the demonstration
  carries them; never EMG (it is not simulated). A *session* (an integer
  seed, :mod:`sandbox.data.synthetic.session`) shows the scene as its tracker
  reports it: the body follows the hand in the tracker's frame.
* :func:`recorded_motion`: replay of a trial ``<root>/<task>/<trial>.csv`` in
  the recorded layout. The robot observes the causally filtered track
  (:func:`sandbox.data.load_trial` with ``preprocess="causal"``: only accepted
  tracker frames, NaN elsewhere); the body follows the smoothed track
  (``"smooth"``), its gaps interpolated. The motion also carries the
  recorded arm (elbow, shoulder) and EMG envelope, preprocessed causally the
  same way, when the trial has them.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np

from sandbox.data.synthetic.families import DIVERGING_VARIABILITY, OBJECTS, diverging_specs
from sandbox.data.synthetic.generator import generate
from sandbox.data.synthetic.intent import intent_switch_demo
from sandbox.data.synthetic.tasks import TaskSpec, Variability
from sandbox.envs.human import BODY_DIMS, HumanMotion

#: Synthetic families and their tasks.
FAMILIES = ("objects", "diverging")
#: Modalities a synthetic motion is generated with (the hand is the same without the arm).
SYNTHETIC_OBSERVE = ("hand", "arm")
#: Modalities a recorded replay loads (each as in evaluation: ``preprocess="causal"``).
RECORDED_OBSERVE = ("hand", "arm", "emg")


def family_specs(family: str) -> tuple[tuple[TaskSpec, ...], Variability]:
    """Task specs and variability of a synthetic ``family`` (one of :data:`FAMILIES`)."""
    if family == "objects":
        return OBJECTS, Variability()
    if family == "diverging":
        return diverging_specs(), DIVERGING_VARIABILITY
    raise ValueError(f"family: expected one of {list(FAMILIES)}, got {family!r}")


def family_tasks(family: str) -> tuple[str, ...]:
    """Task names of a synthetic ``family``."""
    return tuple(spec.name for spec in family_specs(family)[0])


def synthetic_motion(family: str, task: str, rng: np.random.Generator, *,
                     switch_to: str | None = None, switch_phase: float = 0.5,
                     session: int | None = None) -> HumanMotion:
    """One synthetic hand motion of ``task``.

    Parameters
    ----------
    family : str
        One of :data:`FAMILIES`.
    task : str
        One of the family's tasks (:func:`family_tasks`).
    rng : numpy.random.Generator
        Source of randomness (the environment's ``np_random``).
    switch_to : str, optional
        Another task of the family the human switches to at ``switch_phase``
        of the motion (an intent switch); the episode's task is then this one.
    switch_phase : float
        Fraction of the motion's duration at which the intent switches.
    session : int, optional
        A recording session's seed (>= 0; not with ``switch_to``): ``true``
        is then the hand as a noiseless tracker of the session reports it
        (``meta["tracked_clean"]`` of the demonstration: the scene is in the
        robot's frame as the tracker reports the hand), ``measured`` the
        tracked hand with its artefacts, and ``meta["session"]`` the session
        (:meth:`~sandbox.data.synthetic.session.Session.to_dict`).

    Returns
    -------
    HumanMotion
        ``meta["handover_target"]`` (3,) m is where the demonstrated gripper
        tip met the hand (Baxter's base frame); ``meta["meeting_offset"]``
        (3,) m the tip minus ``true`` at the meeting (both arrived; the last
        row for an intent switch); ``meta["robot"]``: the demonstration's
        robot, ``{"times": (T,) s, "joints": (T, 7) rad}`` on the motion's
        unscaled times (so an oracle policy can replay it).
    """
    demo, meta = _synthetic_demo(family, task, rng, switch_to, switch_phase, session)
    times = demo.times - demo.times[0]
    true = demo.meta.get("tracked_clean", demo.meta["clean_human"])
    return HumanMotion(
        times=times, true=true, measured=demo.select("hand").human, task=demo.task,
        source=demo.source, body=demo_body(demo),
        meta={**meta, "handover_target": np.array(demo.meta["handover_target"]),
              "meeting_offset": _meeting_offset(demo, true),
              "robot": {"times": times, "joints": np.array(demo.robot)}},
    )


def _synthetic_demo(family: str, task: str, rng: np.random.Generator, switch_to: str | None,
                    switch_phase: float, session: int | None):
    """The demonstration of :func:`synthetic_motion` and the motion's ``meta`` it gives."""
    specs, variability = family_specs(family)
    by_name = {spec.name: spec for spec in specs}
    for name in (task, switch_to) if switch_to is not None else (task,):
        if name not in by_name:
            raise ValueError(f"task: expected one of {list(by_name)} ({family}), got {name!r}")
    if session is not None and switch_to is not None:
        raise ValueError(f"session: expected None with switch_to (an intent switch has no "
                         f"session), got {session!r}")
    if switch_to is None:
        (demo,) = generate([by_name[task]], 1, rng, family=family, variability=variability,
                           observe=SYNTHETIC_OBSERVE, session=session)
        return demo, ({} if session is None else {"session": demo.meta["session"]})
    demo, truth = intent_switch_demo(task, switch_to, switch_phase, rng, family=family,
                                     observe=SYNTHETIC_OBSERVE)
    return demo, {"intent": truth}


def _meeting_offset(demo, true: np.ndarray) -> np.ndarray:
    """The fingertip minus ``true`` (T, 3) m at the demonstration's meeting, shape (3,) m.

    A session's demonstration has it (``meta["meeting_offset"]``); otherwise
    the meeting is the first row both the hand and the robot have arrived
    (the last row for an intent switch).
    """
    from sandbox.data.synthetic.robot import kinematics
    from sandbox.data.synthetic.tails import meeting_row
    from sandbox.robot import TIP_LINK

    if "meeting_offset" in demo.meta:
        return np.array(demo.meta["meeting_offset"])
    meta, row = demo.meta, len(demo.times) - 1
    if "reach_time" in meta and "robot_time" in meta:
        row = meeting_row(demo.times, meta["reach_time"], meta["robot_time"])
    return kinematics().fk(demo.robot[row], link=TIP_LINK) - true[row]


def episode_motion(episode, family: str, rng: np.random.Generator):
    """The hand motion of an episode's options (:class:`~sandbox.envs.options.EpisodeOptions`).

    The scripted ``motion``, a teleoperated hand (``source="teleop"``), a synthetic
    reach of ``family`` (a random task of it unless given) or a recorded trial;
    played ``episode.speed`` times faster. ``rng``: the environment's ``np_random``.
    """
    from sandbox.envs.teleop import TeleopMotion

    if episode.motion is not None:
        motion = episode.motion
    elif episode.source == "teleop":
        motion = TeleopMotion(rng, task=episode.task or "teleop")
    elif episode.source == "synthetic":
        tasks = family_tasks(family)
        task = episode.task or tasks[int(rng.integers(len(tasks)))]
        motion = synthetic_motion(family, task, rng, switch_to=episode.switch_to,
                                  switch_phase=episode.switch_phase, session=episode.session)
    else:
        motion = recorded_motion(episode.source, episode.task, episode.trial, rng)
    return motion if episode.speed == 1.0 else motion.scaled(episode.speed)


def demo_body(demo) -> dict[str, np.ndarray]:
    """The body modalities (:data:`~sandbox.envs.human.BODY_DIMS`) a demonstration carries.

    Parameters
    ----------
    demo : Demonstration
        Its ``human`` columns of modality ``arm`` (6 dims, m) and ``emg`` (8)
        are taken where present; the others are left out (unobserved).

    Returns
    -------
    dict
        Modality name -> values, shape (T, dims), NaN where nothing was measured.
    """
    names = [m.name for m in demo.modalities]
    return {name: demo.select(name).human for name in BODY_DIMS if name in names}


def recorded_trials(root: str | Path, task: str | None = None) -> list[tuple[str, Path]]:
    """``(task, file)`` of every trial under ``root`` (of ``task`` only if given)."""
    from sandbox.data.recorded import find_trials

    return find_trials(root, None if task is None else [task])


def pick_trial(trials: list[tuple[str, Path]], trial: int | str | None,
               rng: np.random.Generator) -> tuple[str, Path]:
    """Choose one of ``trials``: by index, by file name (with or without ``.csv``), or at random."""
    if trial is None:
        return trials[int(rng.integers(len(trials)))]
    if isinstance(trial, (int, np.integer)) and not isinstance(trial, bool):
        if not 0 <= int(trial) < len(trials):
            raise ValueError(f"trial: expected an index in [0, {len(trials) - 1}], got {trial}")
        return trials[int(trial)]
    if isinstance(trial, str):
        for task, path in trials:
            if trial in (path.name, path.stem):
                return task, path
        names = ", ".join(p.stem for _, p in trials[:5])
        raise ValueError(f"trial: expected a file name among the trials ({names}, ...), "
                         f"got {trial!r}")
    raise ValueError(f"trial: expected an index, a file name or None, got {trial!r}")


def recorded_motion(root: str | Path, task: str | None, trial: int | str | None,
                    rng: np.random.Generator) -> HumanMotion:
    """Replay of one recorded trial (random task and trial where not given)."""
    trials = recorded_trials(root, task)
    return _load_motion(*map(str, pick_trial(trials, trial, rng)))


@functools.lru_cache(maxsize=64)
def _load_motion(task: str, path: str) -> HumanMotion:
    from sandbox.data.recorded import load_trial

    causal = _load_causal(task, path)
    return motion_of(load_trial(path, task=task, preprocess="smooth"), causal)


def motion_of(smooth, causal) -> HumanMotion:
    """The replay of one recorded trial: the ``hand`` of ``smooth`` (its smoothed version) as
    the true motion, ``causal``'s as measured, its other body modalities as observed.

    Both are the same trial loaded with the two preprocessings (same time stamps).
    """
    times = causal.times - causal.times[0]
    hand = smooth.select("hand").human
    true = np.column_stack([_fill(times, hand[:, j]) for j in range(3)])
    return HumanMotion(times=times, true=true, measured=causal.select("hand").human,
                       task=causal.task, source=causal.source,
                       meta={"report": causal.meta["report"]}, body=demo_body(causal))


def _load_causal(task: str, path: str):
    """The trial as the evaluation's test streams see it: :data:`RECORDED_OBSERVE`, causal.

    A modality the trial lacks or cannot use (missing columns, a constant
    signal, fewer than 2 valid frames) is left out, so it is unobserved.
    """
    from sandbox.data.recorded import load_trial

    try:
        return load_trial(path, task=task, observe=RECORDED_OBSERVE, preprocess="causal")
    except ValueError:
        pass
    usable = ["hand"]
    for name in RECORDED_OBSERVE[1:]:
        try:
            load_trial(path, task=task, observe=("hand", name), preprocess="causal")
            usable.append(name)
        except ValueError:
            continue
    return load_trial(path, task=task, observe=usable, preprocess="causal")


def _fill(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    ok = np.isfinite(y)
    if not ok.any():
        raise ValueError("recorded trial: the smoothed hand track has no valid sample")
    return np.interp(t, t[ok], y[ok])


def minimum_jerk(times: np.ndarray, waypoint_times: np.ndarray,
                 waypoints: np.ndarray) -> np.ndarray:
    """Positions (T, 3) m at ``times`` (s) of a path through ``waypoints`` (W, 3) m.

    Between consecutive waypoints the hand follows a minimum-jerk segment
    (zero velocity and acceleration at each waypoint,
    s(u) = 10 u^3 - 15 u^4 + 6 u^5); it holds the first waypoint before
    ``waypoint_times[0]`` and the last one after ``waypoint_times[-1]``.
    """
    i = np.clip(np.searchsorted(waypoint_times, times, side="right"), 1, len(waypoint_times) - 1)
    t0, t1 = waypoint_times[i - 1], waypoint_times[i]
    u = np.clip((times - t0) / (t1 - t0), 0.0, 1.0)[:, None]
    s = u**3 * (10.0 - 15.0 * u + 6.0 * u**2)
    return waypoints[i - 1] + s * (waypoints[i] - waypoints[i - 1])


def waypoint_motion(waypoint_times, waypoints, rng: np.random.Generator, *,
                    task: str = "scripted", tracker=None, rate_hz: float = 100.0,
                    hold_s: float = 0.5) -> HumanMotion:
    """A scripted hand motion through timed waypoints, observed through the tracker model.

    Parameters
    ----------
    waypoint_times : array_like, shape (W,)
        When the hand is at each waypoint (s), strictly increasing, the first >= 0
        (the hand waits at the first waypoint until then).
    waypoints : array_like, shape (W, 3)
        Hand positions (m, Baxter's base frame); W >= 2.
    rng : numpy.random.Generator
        Draws the tracker's noise and frame timing.
    task : str
        The episode's task label.
    tracker : TrackerModel, optional
        Tracker artefacts (default: noise and 30 Hz frames, no jumps).
    rate_hz : float
        Sample rate of the motion (Hz).
    hold_s : float
        The motion goes on this long (s) after the last waypoint (the hand holds still).

    Returns
    -------
    HumanMotion
        ``meta["waypoints"]`` and ``meta["waypoint_times"]`` hold the script.
    """
    from sandbox.data.synthetic.tracker import TrackerModel, apply_tracker
    from sandbox.validation import check_array, check_positive, check_times

    waypoint_times = check_times(waypoint_times, "waypoint_times")
    if waypoint_times[0] < 0:
        raise ValueError(f"waypoint_times: expected times >= 0 (s), got {waypoint_times[0]:g}")
    waypoints = check_array(waypoints, "waypoints", 2, shape=(waypoint_times.size, 3))
    rate_hz = check_positive(rate_hz, "rate_hz")
    end = waypoint_times[-1] + check_positive(hold_s, "hold_s", allow_zero=True)
    times = np.arange(0.0, end + 0.5 / rate_hz, 1.0 / rate_hz)
    true = minimum_jerk(times, waypoint_times, waypoints)
    model = tracker if tracker is not None else TrackerModel(glitch_rate=0.0)
    measured = apply_tracker(times, true, model, rng)
    return HumanMotion(times=times, true=true, measured=measured, task=task,
                       source=f"waypoints[{waypoint_times.size}]",
                       meta={"waypoints": waypoints, "waypoint_times": waypoint_times})
