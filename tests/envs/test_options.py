"""``reset(options=...)``: validation and what each option does."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.envs.options import OPTION_KEYS, EpisodeOptions, parse_options


def test_defaults():
    assert parse_options(None, "diverging") == EpisodeOptions()
    assert parse_options({}, "objects") == EpisodeOptions()


def test_valid_options_are_kept(tmp_path):
    opts = parse_options({"task": "up", "object": "tape", "speed": 2, "switch_to": "down",
                          "switch_phase": 0.4}, "diverging")
    assert (opts.task, opts.object, opts.speed, opts.switch_to, opts.switch_phase) == (
        "up", "tape", 2.0, "down", 0.4)
    recorded = parse_options({"source": tmp_path, "task": "anything", "trial": 3}, "objects")
    assert recorded.source == str(tmp_path) and recorded.trial == 3


@pytest.mark.parametrize("options, match", [
    ({"colour": "red"}, "expected keys among"),
    ({"grasp_offset": [0.0, 0.1]}, r"grasp_offset: expected 3 finite numbers"),
    ({"grasp_offset": [0.0, 0.5, 0.0]}, r"grasp_offset: expected .* within 0.3 m"),
    ({"grasp_offset": [0.0, np.nan, 0.0]}, r"grasp_offset: expected 3 finite numbers"),
    ({"grasp_offset": "near"}, r"grasp_offset: expected 3 finite numbers"),
    ({"grasp_offset": {}}, r"grasp_offset: expected task names -> offsets"),
    ({"grasp_offset": {"up": [1, 1, 1]}}, r"grasp_offset\['up'\]: expected"),
    ({"task": "left"}, "task: expected one of .*objects"),
    ({"task": 3}, "task: expected a task name"),
    ({"object": "banana"}, "object: expected one of"),
    ({"source": "/no/such/folder"}, "source: expected 'synthetic', 'teleop' or the folder"),
    ({"source": 42}, "source"),
    ({"speed": 0.0}, "speed: expected a number in"),
    ({"speed": 10}, "speed"),
    ({"speed": "fast"}, "speed"),
    ({"speed": True}, "speed"),
    ({"speed": float("nan")}, "speed"),
    ({"trial": 2}, "trial: only for a recorded source"),
    ({"switch_to": "left"}, "switch_to: expected one of"),
    ({"switch_phase": 0.0}, "switch_phase"),
])
def test_bad_options_are_refused(options, match):
    with pytest.raises(ValueError, match=match):
        parse_options(options, "objects")


def test_switch_needs_the_synthetic_source(tmp_path):
    with pytest.raises(ValueError, match="switch_to: only for the synthetic source"):
        parse_options({"source": str(tmp_path), "switch_to": "box"}, "objects")


def test_options_must_be_a_mapping():
    with pytest.raises(ValueError, match="options: expected a dict"):
        parse_options([("task", "box")], "objects")
    assert "speed" in OPTION_KEYS


def test_env_refuses_bad_options(objects_env):
    # unwrapped: a failing first reset would leave gymnasium's passive checker inconsistent
    with pytest.raises(ValueError, match="object"):
        objects_env.unwrapped.reset(seed=0, options={"object": "banana"})


def test_task_object_and_seed_choose_the_episode(objects_env, diverging_env):
    _, info = objects_env.reset(seed=0, options={"task": "tape"})
    assert (info["task"], info["object"]) == ("tape", "tape")
    _, info = objects_env.reset(seed=0, options={"task": "tape", "object": "screwdriver"})
    assert info["object"] == "screwdriver"
    _, info = diverging_env.reset(seed=0, options={"task": "left"})
    assert (info["task"], info["object"]) == ("left", "box")
    tasks = {diverging_env.reset(seed=s)[1]["task"] for s in range(12)}
    assert len(tasks) >= 3  # drawn with the seed


def test_held_object_is_the_chosen_one(objects_env):
    objects_env.reset(seed=0, options={"task": "box", "object": "measuring_tape"})
    env = objects_env.unwrapped
    hand, _ = env.sim.pose("human_hand")
    assert np.linalg.norm(env.sim.pose("measuring_tape")[0] - hand) < 0.05
    assert np.linalg.norm(env.sim.pose("box")[0] - hand) > 1.0  # parked


def test_speed_scales_the_human_motion(diverging_env):
    _, slow = diverging_env.reset(seed=8, options={"task": "up"})
    _, fast = diverging_env.reset(seed=8, options={"task": "up", "speed": 2.0})
    assert fast["duration"] == pytest.approx(slow["duration"] / 2.0)
    motion = diverging_env.unwrapped.motion
    np.testing.assert_allclose(motion.position(fast["duration"] / 2),
                               motion.true[np.searchsorted(motion.times, fast["duration"] / 2)],
                               atol=0.01)


def test_intent_switch_ends_with_the_second_task(diverging_env):
    _, info = diverging_env.reset(seed=2, options={"task": "left", "switch_to": "right",
                                                   "switch_phase": 0.4})
    assert info["task"] == "right"
    truth = diverging_env.unwrapped.motion.meta["intent"]
    assert truth.tasks == ("left", "right")
    assert truth.switch_time == pytest.approx(0.4 * info["duration"])


def test_session_is_an_integer_for_a_drawn_synthetic_motion(tmp_path):
    assert parse_options({"session": 3}, "objects").session == 3
    assert parse_options({"session": None}, "objects").session is None
    for options, match in [
        ({"session": -1}, "^session: expected an integer >= 0"),
        ({"session": "3"}, "^session: expected an integer >= 0"),
        ({"session": True}, "^session: expected an integer >= 0"),
        ({"session": 2, "source": "teleop"}, "^session: only for a synthetic motion"),
        ({"session": 2, "source": tmp_path}, "^session: only for a synthetic motion"),
        ({"session": 2, "switch_to": "tape"}, "^session: only for a synthetic motion"),
    ]:
        with pytest.raises(ValueError, match=match):
            parse_options(options, "objects")


def test_reset_with_a_session_is_deterministic_and_shows_the_tracked_hand(objects_env):
    from sandbox.data.synthetic.session import draw_session

    first, _ = objects_env.reset(seed=1, options={"session": 3})
    motion = objects_env.unwrapped.motion
    again, _ = objects_env.reset(seed=1, options={"session": 3})
    assert all(np.array_equal(first[k], again[k]) for k in first)
    np.testing.assert_array_equal(objects_env.unwrapped.motion.true, motion.true)
    assert motion.meta["session"] == draw_session(3).to_dict()
    plain, _ = objects_env.reset(seed=1)
    assert "session" not in objects_env.unwrapped.motion.meta
    assert not np.array_equal(plain["hand"], first["hand"])
