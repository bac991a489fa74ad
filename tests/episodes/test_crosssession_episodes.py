"""Recorded replays across sessions: ``run_scenario("recorded", data=A, test=B)`` and a folder of
sessions replayed leave-one-session-out (issue 21, item 3)."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from sandbox.data.geometry import learn_geometry
from sandbox.data.recorded import load_recorded
from sandbox.episodes.replays import plan_replays
from sandbox.episodes.scenarios import run_scenario
from tests.data.folders import write_synthetic_set

#: Two sessions of the same synthetic:diverging trials (5 tasks, 2 each), tuesday's tracker
#: 4 cm off on every axis: its hand-to-fingertip meeting offsets are 4 cm off the other way.
SHIFTS = {"monday": 0.0, "tuesday": 0.04}


@pytest.fixture(scope="module")
def sessions(tmp_path_factory) -> Path:
    """ROOT/<session>/<task>/<trial>.csv."""
    root = tmp_path_factory.mktemp("sessions")
    for name, shift in SHIFTS.items():
        write_synthetic_set(root / name, "diverging", n_per_task=2, seed=0, shift=shift)
    return root


def offsets(*folders: Path) -> dict:
    """The meeting offsets learned from every (hand) trial of ``folders``."""
    demos = [d for folder in folders for d in load_recorded(folder, observe=("hand",))[0]]
    return learn_geometry(demos).offsets()


def same_offsets(a: dict, b: dict) -> bool:
    return a.keys() == b.keys() and all(np.allclose(a[t], b[t], atol=1e-12) for t in a)


def test_a_set_replayed_against_itself_rides_at_the_geometry_of_all_of_it(sessions):
    monday = sessions / "monday"
    (result,) = run_scenario("recorded", "recorded_robot", n_episodes=1, seed=0, data=monday,
                             test=monday)
    assert same_offsets(result.options["grasp_offset"], offsets(monday))
    assert result.replay == {"mode": "cross-session", "train": str(monday), "n_train": 10,
                             "session": str(monday)}
    assert (monday / result.task / result.options["trial"]).is_file()


def test_cross_session_episodes_ride_at_the_training_sets_geometry(sessions):
    monday, tuesday = sessions / "monday", sessions / "tuesday"
    results = run_scenario("recorded", "recorded_robot", n_episodes=2, seed=1, data=monday,
                           test=tuesday)
    own, training = offsets(tuesday), offsets(monday)
    for result in results:
        assert same_offsets(result.options["grasp_offset"], training)
        assert np.allclose(np.subtract(own[result.task], result.options["grasp_offset"]
                                       [result.task]), -0.04, atol=1e-6)    # not tuesday's
        assert result.options["source"] == str(tuesday)
        assert (tuesday / result.task / result.options["trial"]).is_file()
        assert result.replay["mode"] == "cross-session" and result.replay["n_train"] == 10


def test_the_replayed_sets_size_replays_each_trial_once(sessions):
    replays = plan_replays(sessions / "monday", 10, 3, test=sessions / "tuesday")
    trials = [(r.options["task"], r.options["trial"]) for r in replays]
    assert len(set(trials)) == 10 and [r.seed for r in replays] == list(range(3, 13))
    assert len({id(r.model) for r in replays}) == 1          # one model for all


def test_leave_one_session_out_fits_each_session_on_the_others(sessions):
    replays = plan_replays(sessions, 20, 0)
    assert {r.provenance["session"] for r in replays} == set(SHIFTS)
    learned = {name: offsets(sessions / name) for name in SHIFTS}
    trials = {(r.options["source"], r.options["task"], r.options["trial"]) for r in replays}
    assert len(trials) == 20                                 # every trial once
    for r in replays:
        session = r.provenance["session"]
        (other,) = set(SHIFTS) - {session}
        assert r.options["source"] == str(sessions / session)
        assert same_offsets(r.options["grasp_offset"], learned[other])
        assert r.provenance == {"mode": "leave-one-session-out", "session": session,
                                "train": other, "n_train": 10}
    models = {r.provenance["session"]: id(r.model) for r in replays}
    assert all(id(r.model) == models[r.provenance["session"]] for r in replays)  # fit once


def test_sessions_pooled_for_the_fit_with_a_test_set(sessions):
    (replay,) = plan_replays(sessions, 1, 0, test=sessions / "tuesday")
    assert same_offsets(replay.options["grasp_offset"],
                        offsets(sessions / "monday", sessions / "tuesday"))
    assert replay.provenance["n_train"] == 20


def partial_copy(src: Path, dst: Path, tasks: list[str]) -> Path:
    for task in tasks:
        shutil.copytree(src / task, dst / task)
    return dst


@pytest.mark.parametrize("case, match", [
    ("sessions-as-test", "test: expected one set <root>/<task>/<trial>.csv, got a folder of "
                         "sessions"),
    ("missing-tasks", r"has tasks \['right', 'straight', 'up'\] that"),
    ("session-missing-tasks", r"data: session monday has tasks \['right', 'straight', 'up'\]"),
    ("one-session", "data: expected at least 2 sessions"),
    ("not-recorded", "test: expected a recorded set to replay in the 'recorded' scenario"),
])
def test_what_cannot_run_is_one_line_before_any_episode(sessions, tmp_path, case, match):
    kwargs = {"scenario": "recorded", "policy": "recorded_robot", "n_episodes": 1,
              "data": sessions / "tuesday", "test": sessions / "monday"}
    if case == "sessions-as-test":
        kwargs["test"] = sessions
    elif case == "missing-tasks":
        kwargs["data"] = partial_copy(sessions / "tuesday", tmp_path / "two", ["down", "left"])
    elif case == "session-missing-tasks":
        partial_copy(sessions / "tuesday", tmp_path / "root" / "tuesday", ["down", "left"])
        shutil.copytree(sessions / "monday", tmp_path / "root" / "monday")
        kwargs.update(data=tmp_path / "root", test=None)
    elif case == "one-session":
        shutil.copytree(sessions / "monday", tmp_path / "root" / "monday")
        kwargs.update(data=tmp_path / "root", test=None)
    else:
        kwargs.update(scenario="diverging", policy="dynamic", data=None)
    with pytest.raises(ValueError, match=match) as error:
        run_scenario(**kwargs)
    assert "\n" not in str(error.value)
