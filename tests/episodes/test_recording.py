"""Recorded episodes: beliefs, outcome and summary of an environment episode with a policy."""

from __future__ import annotations

import json

import numpy as np
import pytest

import sandbox.envs  # noqa: F401  (registers the environments)
from sandbox.episodes.policies import IProMPPolicy, StaticPolicy, fit_family_model
from sandbox.episodes.recording import Belief, EpisodeRecord, record_episode

SWITCH = {"task": "up", "switch_to": "right", "switch_phase": 0.55}


@pytest.fixture(scope="module")
def model():
    return fit_family_model("diverging")


@pytest.fixture(scope="module")
def switch_record(env, model):
    policy = IProMPPolicy(model, dow_t=0.2)
    seen = []
    record = record_episode(env, policy, seed=0, options=SWITCH, policy_name="dynamic",
                            on_update=seen.append)
    return record, policy, seen


def test_beliefs_are_the_predictor_updates(switch_record, model):
    record, policy, seen = switch_record
    assert len(record.updates) == len(policy.predictor.updates) >= 5
    assert seen == record.updates  # reported as they happened
    for belief, update in zip(record.updates, policy.predictor.updates):
        assert belief.time == update.time and belief.task == update.task
        assert list(belief.posterior) == list(model.tasks)
        assert sum(belief.posterior.values()) == pytest.approx(1.0)
        assert belief.jump == update.jump


def test_outcome_matches_the_environment(switch_record):
    record, _, _ = switch_record
    assert record.task == "right" and record.object == "box"
    assert record.success and record.handover_time == pytest.approx(record.end_time)
    assert record.final_distance >= record.min_distance >= 0.0
    assert record.steps == len(record.truth)
    # one recognition per update, at its time; nothing before the first update
    assert record.recognised == [(b.time, b.task) for b in record.updates]
    assert record.truth[0][1] == "up" and record.truth[-1][1] == "right"  # the intent switch
    assert record.recognised_at(record.end_time) == record.recognised[-1][1]
    assert record.recognised_at(-1.0) == ""


def test_summary_is_json_ready(switch_record):
    record, _, _ = switch_record
    summary = json.loads(json.dumps(record.summary()))
    assert summary["success"] is True and summary["policy"] == "dynamic"
    assert summary["n_updates"] == len(summary["updates"]) == len(record.updates)
    assert summary["final_task"] == record.recognised[-1][1]
    times = [r["time"] for r in summary["recognised"]]
    assert times == sorted(times)
    tasks = [r["task"] for r in summary["recognised"]]
    assert all(a != b for a, b in zip(tasks, tasks[1:]))  # only the changes
    update_times = {round(b.time, 4) for b in record.updates}
    assert set(times) <= update_times     # one clock: a change happens at an update's time
    assert {"familiarity", "moving"} <= set(summary["updates"][0])


def test_static_policy_and_step_limit(env, model):
    record = record_episode(env, StaticPolicy(model, ratio=0.3), seed=1, max_steps=40)
    assert record.steps == 40 and record.end_time == pytest.approx(0.8)
    assert len(record.updates) <= 1 and record.truth == []
    assert record.summary()["handover_time_s"] is None


def test_viewer_records_the_bodies_and_the_overlays(env, model):
    from sandbox.viz import Viewer

    viewer = Viewer(fps=10.0)
    viewer.add_simulation(env.unwrapped.sim)
    overlay = viewer.add_overlay(model.tasks, rng=np.random.default_rng(0))
    record_episode(env, IProMPPolicy(model), seed=2, viewer=viewer, overlay=overlay,
                   max_steps=30)
    assert viewer.scene.timeline.n_frames == 7  # 0 .. 0.6 s at 10 fps
    paths = list(viewer.scene.nodes)
    assert any("overlays/human" in p for p in paths)
    assert any("overlays/prediction" in p for p in paths)


def test_belief_dict_turns_nan_into_none():
    belief = Belief(time=0.1, task="a", posterior={"a": 1.0}, duration=float("nan"))
    assert belief.as_dict()["duration"] is None
    assert EpisodeRecord(task="a", object="box", source="x").summary()["final_task"] == ""


def test_warnings_count_the_unfamiliar_updates():
    from sandbox.episodes.recording import warnings

    def b(t, familiar):
        return Belief(time=t, task="a", posterior={"a": 1.0}, duration=1.0, familiar=familiar)

    assert warnings([]) == {"unfamiliar_updates": None, "first_warning_s": None}
    assert warnings([b(0.2, None)])["unfamiliar_updates"] is None
    assert warnings([b(0.2, True), b(0.4, True)]) == {"unfamiliar_updates": 0,
                                                      "first_warning_s": None}
    assert warnings([b(0.2, True), b(0.4, False), b(0.6, True), b(0.8, False)]) == {
        "unfamiliar_updates": 2, "first_warning_s": 0.4}


def test_an_unfamiliar_motion_is_in_the_summary_and_the_replay(env, model):
    """Issue 30 item 6: with a calibration of motions that fitted far better than any real
    stream can, every update is unfamiliar: the summary says when the warning came, the
    replay shows it."""
    import copy

    from sandbox.core.familiarity import Calibration
    from sandbox.viz import Viewer

    rng = np.random.default_rng(0)
    K = len(model.tasks)
    records = [(np.arange(1, 11) * 0.2, 1e-9 * rng.lognormal(size=10), np.full(10, k))
               for k in range(K) for _ in range(25)]
    unsure = copy.copy(model)
    unsure.calibration = Calibration.from_records(records, K)
    viewer = Viewer(fps=10.0)
    viewer.add_simulation(env.unwrapped.sim)
    overlay = viewer.add_overlay(unsure.tasks, rng=np.random.default_rng(0))
    record = record_episode(env, IProMPPolicy(unsure, dow_t=0.2), seed=2, viewer=viewer,
                            overlay=overlay, max_steps=40)
    summary = record.summary()
    assert record.updates and all(b.familiar is False for b in record.updates)
    assert summary["first_warning_s"] == round(record.updates[0].time, 4)
    assert summary["unfamiliar_updates"] == len(record.updates)
    assert summary["updates"][0]["familiar"] is False
    shown = [v for path, props in viewer.scene.timeline.tracks.items()
             if path.endswith("warning_box") for v in props.get("visible", {}).values()]
    assert True in shown           # the warning box appears in the replay
    # an uncalibrated model's summary says nothing about a warning
    plain = record_episode(env, IProMPPolicy(model, dow_t=0.2), seed=2, max_steps=40)
    assert plain.summary()["unfamiliar_updates"] is None
    assert all(b.familiar is None for b in plain.updates)
