"""Scripted scenarios: seeded handover episodes of a chosen scenario and policy.

=================  =========================================================================
scenario           what the human does
=================  =========================================================================
``diverging``      a synthetic diverging reach (left, right, up, down or straight), box
``objects``        a synthetic object handover (box, glasses case or tape)
``intent_switch``  a diverging reach that switches to another direction at 30-60 % of it
``recorded``       a recorded trial replayed (needs ``data``); the model is fitted on the
                   set's other trials (leave-one-out), on all of ``data`` when the trials
                   replayed are another set's (``test``: cross-session), or on the other
                   sessions of a folder of sessions (leave-one-session-out)
=================  =========================================================================

In every scenario the object rides where the model's demonstrations met the hand
(:func:`grasp_options`); in the ``recorded`` one that is never the replayed
trial's own meeting point (:mod:`sandbox.episodes.replays`).

Policies: ``"dynamic"`` (:class:`~sandbox.episodes.policies.IProMPPolicy`, window
``dow_t``), ``"static"`` (:class:`~sandbox.episodes.policies.StaticPolicy`, ``ratio``),
``"recorded_robot"`` (``recorded`` scenario only: the trial's own recorded robot
motion, :class:`~sandbox.episodes.policies.RecordedRobotPolicy`, the reference a
predictor of it can reach) or any callable ``model -> policy``. Synthetic
scenarios use a model fitted on seeded synthetic demonstrations of the family
(:func:`sandbox.episodes.policies.fit_family_model`).
``observe`` chooses the modalities the policy feeds (``hand``, ``arm``,
``emg``); in the ``recorded`` scenario the model is fitted on them too.

Episode ``i`` is ``env.reset(seed=seed + i)``, so a scenario run is reproducible.

Examples
--------
>>> results = run_scenario("diverging", "dynamic", n_episodes=2, seed=0)
>>> summary = summarize(results)
>>> sorted(summary)[:3]
['final_distance_m', 'handover_time_s', 'n_episodes']
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from sandbox.episodes.policy import Policy, beliefs_of, recognitions
from sandbox.episodes.replays import Replay, grasp_options, plan_replays
from sandbox.episodes.rollout import Step, rollout
from sandbox.robot.arms import arm_spec
from sandbox.validation import check_choice

#: Scenario name -> (environment id, synthetic family).
SCENARIOS = {
    "diverging": ("sandbox/BaxterHandoverDiverging-v1", "diverging"),
    "objects": ("sandbox/BaxterHandover-v1", "objects"),
    "intent_switch": ("sandbox/BaxterHandoverDiverging-v1", "diverging"),
    "recorded": ("sandbox/BaxterHandover-v1", None),
}
POLICIES = ("dynamic", "static", "recorded_robot", "bip", "ebip", "dtw", "nearest")


@dataclass(frozen=True)
class EpisodeResult:
    """What happened in one episode.

    Attributes
    ----------
    seed : int
        The episode's ``reset`` seed.
    task : str
        The human's task (for an intent switch, the task switched to).
    object : str
    success : bool
        Whether the handover happened.
    handover_time : float or None
        When (s from the episode's start).
    final_distance : float
        Fingertip to the object's grasp point (m) at the end of the episode
        (the grasp point rides in the human hand until the handover).
    min_distance : float
        Smallest such distance (m) during the episode.
    recognised : tuple of (float, str)
        (time s, task) on the updates' clock (:func:`~sandbox.episodes.policy.recognitions`):
        a predictor's task after each update, nothing before its first.
    steps : int
    options : dict
        The ``reset`` options used.
    replay : dict
        ``recorded`` scenario: where the replayed trial comes from and what its
        model was fitted on (``mode``, ``session``, ``train``, ``n_train``:
        :class:`sandbox.episodes.replays.Replay`); ``{}`` otherwise.
    outcome : str
        ``"handover"``; ``"unreachable"``: no handover and the arm could not reach the
        policy's last goal (``unreachable`` of :class:`sandbox.episodes.steering.Steering`);
        ``"missed"``: no handover otherwise.
    reach : float or None
        Another arm than Baxter, or a task-space model: the fraction of the model's
        meeting points the arm reaches (:func:`sandbox.episodes.steering.reach_report`).
    note : str
        ``"... retargeted ..."`` when a Baxter joint-space model drives another arm.
    """

    seed: int
    task: str
    object: str
    success: bool
    handover_time: float | None
    final_distance: float
    min_distance: float
    recognised: tuple[tuple[float, str], ...]
    steps: int
    options: dict = field(default_factory=dict)
    replay: dict = field(default_factory=dict)
    outcome: str = ""
    reach: float | None = None
    note: str = ""

    @property
    def final_task(self) -> str:
        """The task recognised at the end (``""`` if no step was taken)."""
        return self.recognised[-1][1] if self.recognised else ""


def run_scenario(scenario: str = "diverging", policy: str | Callable = "dynamic", *,
                 n_episodes: int = 20, seed: int = 0, dow_t: float = 0.2, ratio: float = 0.3,
                 data: str | Path | None = None, test: str | Path | None = None, env=None,
                 model=None, options: Mapping[str, Any] | None = None,
                 observe: Sequence[str] | str | None = None, session: int | None = None,
                 train_session: int | None = None, spec=None,
                 robot: str = "baxter") -> list[EpisodeResult]:
    """Run ``n_episodes`` seeded episodes of ``scenario`` with ``policy``; a list of
    :class:`EpisodeResult`, one per episode.

    Parameters
    ----------
    scenario : str
        One of :data:`SCENARIOS`.
    policy : {"dynamic", "static", "recorded_robot"} or callable
        The controller, or a factory ``model -> policy`` (a
        :class:`~sandbox.episodes.policy.Policy`: it maps an observation to an
        action, has ``reset()`` and ``beliefs``; one with a ``task`` attribute
        instead of ``beliefs`` is accepted too).
    n_episodes, seed : int
        Episodes (>= 1); episode ``i`` resets with ``seed + i``.
    dow_t, ratio : float
        Window (s) of the dynamic policy; observed fraction of the static one.
    data, test : str or Path, optional
        ``recorded`` scenario only (:func:`sandbox.episodes.replays.plan_replays`):
        ``data`` one set (leave-one-out) or a folder of sessions (leave-one-session-out);
        with ``test`` (one set, its tasks among ``data``'s), ``test``'s trials are
        replayed with one model of all of ``data``, in ``data``'s meeting geometry.
    env : gymnasium.Env, optional
        An environment made from the scenario's id, reused (not closed); default: a new one.
    model : IProMP, optional
        Synthetic scenarios; default fitted on 20 demos per task of the family (seed 0)
        of the ``observe`` modalities (default the hand).
    options : mapping, optional
        Extra ``reset`` options for every episode (e.g. ``{"speed": 1.5}``).
    observe : sequence of str or str, optional
        Modalities the ``"dynamic"``/``"static"`` policy feeds (``"hand,arm,emg"``
        or a list; each must be the model's). Default: every modality of the
        model the environment observes; ``recorded``: the hand (the model is
        fitted on the ``observe`` modalities loaded from the set).
    session, train_session : int, optional
        ``diverging``/``objects``: the episodes are motions of synthetic session
        ``session``, the model is fitted on ``train_session``'s demos (default the
        same) and ``recorded_robot`` replays each motion's own robot
        (:mod:`sandbox.episodes.sessions`).
    spec : DataSpec, optional
        ``recorded`` only: the sets' layout (:func:`~sandbox.episodes.replays.plan_replays`).
    robot : str
        The arm (:data:`sandbox.robot.arms.ROBOTS`); another than Baxter is retargeted."""
    sessions = (session, train_session)
    observe = _check_run(scenario, policy, n_episodes, data, observe, test, sessions)
    make_policy = _policy_factory(policy, dow_t, ratio, observe, robot)
    episodes = _episodes(scenario, int(n_episodes), int(seed), data, model, options or {},
                         observe, test, sessions, spec)
    own_env = env is None
    env = _make_env(scenario, robot) if own_env else env
    try:
        return _run_all(env, episodes, make_policy, robot)
    finally:
        _ = env.close() if own_env else None


def _run_all(env, episodes: list[Replay], make_policy: Callable,
             robot: str) -> list[EpisodeResult]:
    """Every episode in ``env``, each with its reach report (one per model)."""
    reports: dict[int, tuple[float | None, str | None]] = {}
    out = []
    for e in episodes:
        if id(e.model) not in reports:
            reports[id(e.model)] = _reach(e.model, robot)
        reach, note = reports[id(e.model)]
        out.append(replace(run_episode(env, make_policy(e.model, e.demo), e.seed, e.options),
                           replay=e.provenance, reach=reach, note=note or ""))
    return out


def run_episode(env: Any, policy: Policy, seed: int,
                options: Mapping[str, Any]) -> EpisodeResult:
    """One episode of ``policy`` in ``env`` until termination or truncation.

    The recognised task is read from ``policy.beliefs`` (a policy without
    beliefs: its ``task`` attribute) after every step, on the updates' clock
    (:func:`~sandbox.episodes.policy.recognitions`).
    """
    recognised: list[tuple[float, str]] = []
    distances: list[float] = []
    n_updates = [0]

    def on_step(step: Step) -> None:
        assert step.previous is not None
        beliefs = beliefs_of(policy)
        recognised.extend(recognitions(beliefs, n_updates[0], float(step.previous["time"][0])))
        n_updates[0] = len(beliefs.updates)
        distances.append(step.info["distance"])

    last = rollout(env, policy, seed=seed, options=options, on_step=on_step)
    info = last.reset_info
    step_info: dict[str, Any] = last.info if last.n else {
        "is_success": False, "handover_time": None, "distance": np.nan}
    success = bool(step_info["is_success"])
    outcome = ("handover" if success else
               "unreachable" if getattr(policy, "unreachable", False) else "missed")
    return EpisodeResult(
        seed=seed, task=info["task"], object=info["object"],
        success=success, handover_time=step_info["handover_time"],
        final_distance=float(step_info["distance"]), min_distance=float(np.min(distances)),
        recognised=tuple(recognised), steps=last.n, options=dict(options), outcome=outcome)


def summarize(results: list[EpisodeResult]) -> dict[str, float]:
    """Success rate, mean handover time (s, successes only), median final distance (m),
    and the fraction of episodes whose final recognised task is the true one."""
    if not results:
        raise ValueError("results: expected at least one episode, got none")
    times: list[Any] = [r.handover_time for r in results if r.success]
    return {
        "n_episodes": float(len(results)),
        "success_rate": float(np.mean([r.success for r in results])),
        "handover_time_s": float(np.mean(times)) if times else float("nan"),
        "final_distance_m": float(np.median([r.final_distance for r in results])),
        "recognition_rate": float(np.mean([r.final_task == r.task for r in results])),
    }


# ------------------------------------------------------------------ internals
def _reach(model, robot: str) -> tuple[float | None, str | None]:
    """:func:`~sandbox.episodes.steering.reach_report` when the plans are retargeted."""
    if robot == "baxter" and getattr(model, "robot_space", "joint") == "joint":
        return None, None
    from sandbox.episodes.steering import reach_report

    return reach_report(model, robot)


def _make_env(scenario: str, robot: str = "baxter") -> Any:
    import gymnasium as gym

    import sandbox.envs  # noqa: F401  (registers the environments)

    extra: dict[str, Any] = {} if robot == "baxter" else {"robot": robot}
    return gym.make(SCENARIOS[scenario][0], **extra)


def _check_run(scenario, policy, n_episodes, data, observe, test=None,
               sessions=(None, None)) -> tuple[str, ...] | None:
    """Check :func:`run_scenario`'s arguments; return ``observe`` checked."""
    check_choice(scenario, "scenario", tuple(SCENARIOS))
    if not callable(policy):
        check_choice(policy, "policy", POLICIES)
    if isinstance(n_episodes, bool) or int(n_episodes) != n_episodes or n_episodes < 1:
        raise ValueError(f"n_episodes: expected an integer >= 1, got {n_episodes!r}")
    session = _check_sessions(scenario, *sessions)
    if policy == "recorded_robot" and scenario != "recorded" and session is None:
        raise ValueError(f"policy: 'recorded_robot' replays a recorded trial's robot (or a "
                         f"synthetic session's), expected scenario='recorded' or a session, "
                         f"got {scenario!r}")
    if (scenario == "recorded") != (data is not None):
        raise ValueError("data: expected the recorded set's folder for the 'recorded' "
                         f"scenario and nothing otherwise, got scenario={scenario!r}, "
                         f"data={data!r}")
    if test is not None and scenario != "recorded":
        raise ValueError(f"test: expected a recorded set to replay in the 'recorded' scenario "
                         f"only, got scenario={scenario!r}, test={test!r}")
    checked = _check_observe(observe)
    if checked is not None and callable(policy):
        raise ValueError("observe: expected None with a policy factory (it chooses its own "
                         f"modalities), got {checked!r}")
    return checked


def _check_sessions(scenario: str, session, train_session) -> int | None:
    """``session`` checked: only for the diverging and objects scenarios, and needed
    by ``train_session``."""
    from sandbox.episodes.sessions import check_session

    session = check_session(session)
    train = check_session(train_session, "train_session")
    if session is not None and scenario not in ("diverging", "objects"):
        raise ValueError(f"session: expected None for the {scenario!r} scenario (sessions are "
                         f"synthetic: 'diverging' or 'objects'), got {session!r}")
    if train is not None and session is None:
        raise ValueError(f"train_session: expected a session to replay too, got only "
                         f"train_session={train!r}")
    return session


def _check_observe(observe) -> tuple[str, ...] | None:
    """``observe`` as a tuple of names among the environments' modalities (None stays None)."""
    from sandbox.episodes.policies import ENV_MODALITIES

    if observe is None:
        return None
    names = [n.strip() for n in observe.split(",")] if isinstance(observe, str) else observe
    if (not isinstance(names, Sequence) or not names
            or any(n not in ENV_MODALITIES for n in names) or len(set(names)) != len(names)):
        raise ValueError(f"observe: expected distinct modalities among {list(ENV_MODALITIES)}, "
                         f"got {observe!r}")
    return tuple(names)


def _policy_factory(policy, dow_t: float, ratio: float, observe,
                    robot: str = "baxter") -> Callable:
    """``(model, held-out demo or None) -> policy``."""
    arm_spec(robot)                               # an unknown arm: one line, before anything
    if callable(policy):
        return lambda model, demo: policy(model)
    from sandbox.episodes.policies import IProMPPolicy, RecordedRobotPolicy, StaticPolicy

    if policy == "dynamic":
        return lambda model, demo: IProMPPolicy(model, dow_t=dow_t, observe=observe,
                                                robot=robot)
    if policy == "recorded_robot":
        return lambda model, demo: RecordedRobotPolicy.from_demo(demo, arm=robot)
    if policy != "static":
        from sandbox.episodes.method_policy import MethodPolicy

        return lambda model, demo: MethodPolicy(model, policy, dow_t=dow_t, observe=observe,
                                                robot=robot)
    return lambda model, demo: StaticPolicy(model, ratio=ratio, observe=observe, robot=robot)


def _episodes(scenario, n, seed, data, model, options, observe, test=None,
              sessions=(None, None), spec=None) -> list[Replay]:
    """Every episode's seed, model, reset options, replayed demo (or None) and provenance."""
    if scenario == "recorded":
        return plan_replays(data, n, seed, test=test, observe=observe, options=options,
                            spec=spec)
    if spec is not None:
        raise ValueError(f"spec: expected with the recorded scenario (a spec describes "
                         f"recordings), got scenario {scenario!r}")
    if sessions[0] is not None:
        from sandbox.episodes.sessions import session_episodes

        family = SCENARIOS[scenario][1]
        assert family is not None  # sessions are checked to be of a synthetic family
        return session_episodes(family, n, seed, sessions[0],
                                train_session=sessions[1], model=model, options=options,
                                observe=observe)
    from sandbox.episodes.policies import fit_family_model

    if model is None:
        family = SCENARIOS[scenario][1]
        assert family is not None  # only the recorded scenario has no family
        model = fit_family_model(family, observe=observe or ("hand",))
    out = []
    for i in range(n):
        opts = {**grasp_options(model), **options}
        if scenario == "intent_switch":
            rng = np.random.default_rng(seed + i)
            a, b = rng.choice(list(model.tasks), size=2, replace=False)
            opts.update(task=str(a), switch_to=str(b), switch_phase=float(rng.uniform(0.3, 0.6)))
        out.append(Replay(seed + i, model, opts, None, {}))
    return out
