"""Running a scenario file: its model, its policy, its reset options, the episode to a summary.

:func:`run_scenario_file` runs a :class:`~sandbox.episodes.scenario_files.Scenario`
(read and validated by :func:`~sandbox.episodes.scenario_files.load_scenario`)
with :func:`~sandbox.episodes.recording.record_episode`; :func:`build_model`,
:func:`make_policy` and :func:`reset_options` are its parts.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from sandbox.episodes.scenario_files import HUMAN_KEYS, Scenario


def build_model(scenario: Scenario):
    """The scenario's IProMP: a saved file, the recorded set minus the trial, or synthetic;
    fitted ones carry the meeting geometry of their demonstrations."""
    from sandbox.core import IProMP
    from sandbox.data.geometry import attach_geometry

    if "file" in scenario.model:
        return IProMP.load(scenario.model["file"])
    options = scenario.model.get("options", {})
    if scenario.human_kind == "recorded":
        import warnings

        from sandbox.data.recorded import SkippedTrialWarning, load_recorded
        from sandbox.data.skipped import no_usable

        held_out = Path(scenario.human["file"]).resolve()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", SkippedTrialWarning)      # counted in the error
            demos, skipped = load_recorded(scenario.human["recorded"], observe=scenario.observe,
                                           spec=scenario.human.get("spec"))
        if not demos:
            raise no_usable(f"human.recorded {scenario.human['recorded']}",
                            [f"skipped {f}: {r}" for f, r in skipped])
        # Any: a Demonstration is frozen, the core's DemonstrationLike declares plain attributes
        others: list[Any] = [d for d in demos if Path(d.source).resolve() != held_out]
        return attach_geometry(IProMP(**options).fit(others), others)
    return fit_family(scenario.family, scenario.model["demos"], scenario.model["seed"],
                      scenario.observe, options)


def fit_family(family: str, demos: int, seed: int, observe, options: Mapping | None = None):
    """An IProMP fitted on ``demos`` synthetic demonstrations per task of ``family``.

    ``observe``: modalities (names or ``"a,b"``); ``options``: IProMP options
    (with none but ``n_basis`` the model is the cached, calibrated
    :func:`~sandbox.episodes.policies.fit_family_model`; with others it is fitted
    here and not calibrated).
    """
    from sandbox.episodes.policies import fit_family_model

    options = dict(options or {})
    names = [n.strip() for n in observe.split(",")] if isinstance(observe, str) else observe
    if set(options) <= {"n_basis"}:
        return fit_family_model(family, n_per_task=demos, seed=seed, observe=names,
                                n_basis=options.get("n_basis"), calibrated=True)
    import numpy as np

    from sandbox.core import IProMP
    from sandbox.data.geometry import attach_geometry
    from sandbox.data.synthetic import make_dataset

    made: list[Any] = make_dataset(family, demos, np.random.default_rng(seed),
                                   observe=list(names))
    return attach_geometry(IProMP(**options).fit(made), made)


def make_policy(scenario: Scenario, model):
    """The scenario's policy for ``model``; bad ``options`` become ``ValueError``."""
    from sandbox.episodes.policies import IProMPPolicy, StaticPolicy

    spec = scenario.policy
    try:
        options = {"observe": list(scenario.observe), **spec["options"]}
        if spec["type"] == "dynamic":
            return IProMPPolicy(model, dow_t=spec["dow_t"], robot=scenario.robot, **options)
        return StaticPolicy(model, ratio=spec["ratio"], robot=scenario.robot, **options)
    except (TypeError, ValueError) as error:
        raise ValueError(f"scenario {scenario.path}: policy.options: {error}") from None


def reset_options(scenario: Scenario, model=None) -> dict[str, Any]:
    """``env.reset`` options of the scenario (the scripted motion built here); with
    ``model``, the object rides at its meeting geometry (:func:`grasp_options`)."""
    from sandbox.episodes.scenarios import grasp_options

    opts: dict[str, Any] = {"speed": scenario.speed}
    if model is not None:
        scripted = scenario.human_kind not in ("synthetic", "recorded")
        opts.update(grasp_options(model, task=scenario.human["task"] if scripted else None))
    if scenario.object is not None:
        opts["object"] = scenario.object
    human = scenario.human
    if scenario.human_kind == "synthetic":
        opts.update({k: human[k] for k in HUMAN_KEYS["synthetic"] if human.get(k) is not None})
    elif scenario.human_kind == "recorded" and human.get("spec") is not None:
        from sandbox.episodes.replays import spec_motion  # a layout the env cannot read

        opts["motion"] = spec_motion(human["file"], human["task"], human["spec"], scenario.observe)
    elif scenario.human_kind == "recorded":
        opts.update(source=human["recorded"], task=human.get("task"), trial=human.get("trial"))
    else:
        import numpy as np

        from sandbox.envs.sources import waypoint_motion

        opts["motion"] = waypoint_motion(human["times"], human["points"],
                                         np.random.default_rng(scenario.seed),
                                         task=human["task"], tracker=human["tracker"])
    return opts


def run_scenario_file(scenario: Scenario, *, html: str | Path | None = None,
                      on_update=None, wrap_env=None, on_close=None) -> dict[str, Any]:
    """Run a scenario to the end; write the replay to ``html`` (if given); return the summary.

    ``wrap_env(env)`` returns the env to run (e.g. a ``minari.DataCollector``);
    ``on_close(env)`` is called with it before it is closed.

    Returns
    -------
    dict
        JSON-ready: the scenario (name, file, seed, policy), the outcome
        (:meth:`~sandbox.episodes.recording.EpisodeRecord.summary`: success, handover
        time, final gripper-to-object distance, recognised task over time,
        updates), the intent switch when there is one, the replay's path.
    """
    import gymnasium as gym

    import sandbox.envs  # noqa: F401  (registers the environments)
    from sandbox.episodes.recording import record_episode

    if html is not None and Path(html).suffix.lower() not in (".html", ".htm"):
        raise ValueError(f"html: expected a file name ending in .html, got {str(html)!r}")
    model = build_model(scenario)
    policy = make_policy(scenario, model)
    options = reset_options(scenario, model)
    extra: dict[str, Any] = {} if scenario.robot == "baxter" else {"robot": scenario.robot}
    env: Any = gym.make(scenario.env_id, max_episode_steps=max(1, round(scenario.time_limit * 50)),
                        **extra)
    env = env if wrap_env is None else wrap_env(env)
    viewer = overlay = None
    try:
        if html is not None:
            viewer, overlay = _replay_viewer(env, model, scenario)
        record = record_episode(env, policy, seed=scenario.seed, options=options, viewer=viewer,
                                overlay=overlay, policy_name=scenario.policy["type"],
                                on_update=on_update)
        intent = env.unwrapped.motion.meta.get("intent")
        if on_close is not None:
            on_close(env)
    finally:
        env.close()
    summary = {"scenario": scenario.name, "file": str(scenario.path), "seed": scenario.seed,
               "human": scenario.human_kind, "policy_spec": scenario.policy,
               "observe": list(scenario.observe), "robot": scenario.robot,
               "model_tasks": list(model.tasks), **record.summary()}
    if intent is not None:
        summary["intent_switch"] = {"from": intent.tasks[0], "to": intent.tasks[1],
                                    "time_s": round(float(intent.switch_time), 4)}
    if viewer is not None:
        summary["replay"] = str(viewer.save_html(html))
    return summary


def _replay_viewer(env, model, scenario: Scenario):
    """An offline viewer mirroring ``env`` (bodies, tracked arm) and its prediction overlay."""
    import numpy as np

    from sandbox.viz import Viewer

    viewer = Viewer(fps=30.0)
    viewer.add_simulation(env.unwrapped.sim)
    viewer.add_tracked_arm(env.unwrapped.tracked_arm)
    overlay = viewer.add_overlay(model.tasks, rng=np.random.default_rng(scenario.seed),
                                 title=f"{scenario.name} ({scenario.policy['type']})")
    return viewer, overlay
