"""The spec keys of issue 28 (time, rate_hz, units, frame, files, labels, segment,
resample_hz) and issue 27 item 7 (a signal modality's preprocess): each value checked with
a one-line error naming the key, and each doing what it says on known answers."""

from __future__ import annotations

import csv

import numpy as np
import pytest

from sandbox.data.recorded import load_recorded, load_trial
from sandbox.data.segment import Bound, Segment, bounds, hand_speed, thin
from sandbox.data.signals import preprocess_signal
from sandbox.data.spec import DataSpec
from sandbox.data.spec_frame import parse_frame, suggest_frame
from sandbox.data.spec_read import part_files

HAND = {"columns": ["hx", "hy", "hz"], "kind": "position"}


def _spec(**keys) -> DataSpec:
    return DataSpec.from_dict({"robot": ["q"], "observe": ["hand"],
                               "modalities": {"hand": HAND}, **keys})


def _write(path, header, rows) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as fh:
        out = csv.writer(fh)
        out.writerow(header)
        out.writerows(rows)


@pytest.mark.parametrize(("keys", "message"), [
    ({"units": "inch"}, r"^units: expected one of \['m', 'cm', 'mm'\] .*got 'inch'$"),
    ({"modalities": {"hand": {**HAND, "units": "ft"}}},
     r"^modalities\.hand\.units: expected one of \['m', 'cm', 'mm'\]"),
    ({"rate_hz": 120, "time": "t"}, r"^rate_hz: expected either rate_hz .* or a time column"),
    ({"rate_hz": -1}, r"^rate_hz \(Hz\): expected a finite number > 0"),
    ({"time": {"col": "t"}}, r"^time: unknown keys \['col'\]; expected some of"),
    ({"time": {"column": "t", "unit": "h"}}, r"^time_unit: expected one of \['s', 'ms'"),
    ({"frame": {"yaw": 90, "rpy": [0, 0, 1]}}, r"^frame: expected one of yaw, rpy or "
                                              r"quaternion, got \['yaw', 'rpy'\]$"),
    ({"frame": {"up": "x"}}, r"^frame\.up: expected one of \['y', 'z'\], got 'x'$"),
    ({"frame": {"quaternion": [1, 1, 0, 0]}}, r"^frame\.quaternion: expected a unit quaternion"),
    ({"frame": {"translation": [1, 2]}}, r"^frame\.translation: expected 3 numbers"),
    ({"frame": {"shift": 1}}, r"^frame: unknown keys \['shift'\]; expected some of"),
    ({"files": {"a.b": "x.csv"}}, r"^files: expected part names without dots"),
    ({"files": {"a": "../x.csv"}}, r"^files\.a: expected a file name inside the trial folder"),
    ({"files": {"a": "a.csv"}}, r"^robot: expected columns written part\.column with part one "
                                r"of \['a'\]"),
    ({"labels": {"file": "l.csv", "name": "x"}}, r"^labels: unknown keys \['name'\]"),
    ({"labels": {"trial": "x"}}, r"^labels: 'file' is missing"),
    ({"segment": {"start": {"rule": "speed"}}}, r"^segment\.start\.rule: expected one of "
                                                r"\['onset'\] \(or column: NAME\), got 'speed'"),
    ({"segment": {"end": {"rule": "approach", "hold": 1}}},
     r"^segment\.end: unknown keys \['hold'\]; expected some of \['rule', 'within_m'"),
    ({"segment": {"modality": "emg"}}, r"^segment\.modality: expected a position modality of "
                                       r"3 columns"),
    ({"resample_hz": "fast"}, r"^resample_hz \(Hz\): expected a finite number > 0"),
    ({"modalities": {"f": {"columns": ["f"], "kind": "signal", "preprocess": "rectify"}}},
     r"^modalities\.f\.preprocess: expected one of \['envelope', 'lowpass', 'none'\] for a "
     r"signal modality, got 'rectify'"),
    ({"modalities": {"hand": {**HAND, "preprocess": "lowpass"}}},
     r"^modalities\.hand\.preprocess: .*\(kind 'position'\)$"),
])
def test_every_bad_key_is_one_line_naming_the_key_and_the_choices(keys, message):
    with pytest.raises(ValueError, match=message) as caught:
        _spec(**keys)
    assert "\n" not in str(caught.value)


def test_a_bad_key_in_a_file_names_the_file(tmp_path):
    path = tmp_path / "spec.yaml"
    path.write_text("units: furlong\n")
    with pytest.raises(ValueError, match=r"^spec .*spec\.yaml: units: expected one of"):
        DataSpec.load(path)


def test_time_as_a_mapping_is_time_and_time_unit():
    assert _spec(time={"column": "stamp", "unit": "ms"}) == _spec(time="stamp", time_unit="ms")
    assert _spec(time="stamp").time_unit == "s"


def test_every_key_survives_the_round_trip():
    spec = _spec(rate_hz=120, units="mm", files={"a": "a_*.csv"}, robot=["a.q"],
                 modalities={"hand": {"columns": ["a.x", "a.y", "a.z"], "units": "cm",
                                      "frame": {"rpy": [0, 10, 20]}},
                             "f": {"columns": ["a.f"], "kind": "signal",
                                   "preprocess": "lowpass"}},
                 frame={"translation": [1, 2, 3], "quaternion": [0, 0, 0, 1], "up": "y"},
                 labels={"file": "l.csv", "task": "object"},
                 segment={"start": {"column": "a.go"}, "end": {"rule": "approach"}},
                 resample_hz=60)
    assert DataSpec.from_dict(spec.to_dict()) == spec
    assert spec.layout.length_scale("hand") == 1e-2 and spec.layout.length_scale("arm") == 1e-3
    assert spec.modalities["hand"].units == "m"              # converted as read


def test_frames_on_known_answers():
    yaw = parse_frame({"yaw": 90, "translation": [1, 0, 0]})
    np.testing.assert_allclose(yaw.apply(np.array([[1.0, 0, 0]])), [[1, 1, 0]], atol=1e-12)
    y_up = parse_frame({"up": "y"})
    np.testing.assert_allclose(y_up.apply(np.array([0, 2.0, 0])), [0, 0, 2], atol=1e-12)
    half = np.sqrt(0.5)
    quat = parse_frame({"quaternion": [half, 0, 0, half]})        # 90 degrees about z
    rpy = parse_frame({"rpy": [0, 0, 90]})
    points = np.random.default_rng(0).normal(size=(5, 3))
    np.testing.assert_allclose(quat.apply(points), yaw.apply(points) - [1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(rpy.apply(points), yaw.apply(points) - [1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(yaw.levelled(yaw.apply(points)), points, atol=1e-12)
    kept = np.array([[0.0, 0, 0], [np.nan, 1, 1]])
    out = yaw.apply(kept)
    assert (out[0] == 0).all() and np.isnan(out[1]).all() and (kept[0] == 0).all()


def test_the_suggested_frame_turns_the_reach_toward_the_robot_and_meets_its_point():
    from sandbox.data.spec_frame import meeting_target

    start, meet = meeting_target()
    turn = parse_frame({"yaw": -120, "translation": [3, 1, 0.5]})   # a world of its own
    starts = turn.levelled(np.tile(start, (4, 1)))
    ends = turn.levelled(meet + np.random.default_rng(1).normal(0, 0.01, (4, 3)))
    frame = suggest_frame(starts, ends)
    assert frame.rotation["yaw"] == pytest.approx(-120, abs=2)
    assert np.linalg.norm(frame.apply(ends).mean(axis=0) - meet) < 0.01


def test_units_and_rate_hz_read_millimetres_without_time_as_metres(tmp_path):
    rows = [[1000.0 * i, 20.0, 300.0, 0.1 * i] for i in range(6)]
    _write(tmp_path / "mm" / "up" / "1.csv", ["hx", "hy", "hz", "q"], rows)
    demo = load_trial(tmp_path / "mm" / "up" / "1.csv", spec=_spec(rate_hz=10, units="mm"),
                      preprocess="none")
    np.testing.assert_allclose(demo.times, np.arange(6) / 10)
    np.testing.assert_allclose(demo.human[:, 0], np.arange(6.0))
    np.testing.assert_allclose(demo.human[0], [0.0, 0.02, 0.3])
    assert demo.modalities[0].units == "m"


def test_files_and_labels_join_parts_and_give_tasks(tmp_path):
    for k in range(3):
        n = 5 + k                                           # the second part one row longer
        _write(tmp_path / f"trial{k}" / f"{k}_hand.csv", ["x", "y", "z"],
               [[i, k, 0] for i in range(5)])
        _write(tmp_path / f"trial{k}" / "arm.csv", ["j"], [[0.1 * i] for i in range(n)])
    _write(tmp_path / "stray" / "arm.csv", ["j"], [[0.0]])
    _write(tmp_path / "labels.csv", ["name", "object"],
           [["trial0", "cup"], ["trial1", "pen"], ["trial2", "cup"], ["gone", "pen"]])
    spec = DataSpec.from_dict({"rate_hz": 5, "files": {"h": "*_hand.csv", "r": "arm.csv"},
                               "labels": {"file": "labels.csv", "trial": "name",
                                          "task": "object"},
                               "robot": ["r.j"], "modalities": {"hand": {
                                   "columns": ["h.x", "h.y", "h.z"]}}})
    with pytest.warns(UserWarning):
        demos, skipped = load_recorded(tmp_path, spec=spec, preprocess="none")
    assert [(d.task, d.source[-6:]) for d in demos] == [("cup", "trial0"), ("cup", "trial2"),
                                                        ("pen", "trial1")]
    assert demos[1].human[:, 1].tolist() == [2.0] * 5 and demos[0].robot_names == ("j",)
    assert demos[2].meta["report"]["rows_dropped"] == {"files of unequal length": 1}
    reasons = dict((f.rsplit("/", 1)[-1], r) for f, r in skipped)
    assert reasons == {"stray": "no task for 'stray' in labels.csv",
                       "gone": "labels.csv lists 'gone', not found"}


def _reach(rate: float = 100.0):
    """A pick-up (0.5-1 s), a rest, a reach (2-3 s) to a robot that arrives at 3 s, a hold."""
    t = np.arange(0, 5, 1 / rate)

    def s(a, b):                                    # minimum jerk from 0 to 1 over [a, b]
        x = np.clip((t - a) / (b - a), 0, 1)
        return x**3 * (10 - 15 * x + 6 * x**2)

    hand = np.column_stack([0.3 * s(0.5, 1.0) - 0.6 * s(2.0, 3.0), 0 * t, 0 * t])
    robot = np.column_stack([0.5 - 0.8 * s(1.8, 3.0) + 0.5 * s(4.0, 4.5), 0 * t, 0 * t])
    return t, hand, robot


def test_the_segment_rules_find_the_reach_and_the_meeting():
    t, hand, robot = _reach()
    seg = Segment("hand", Bound(rule="onset", value=0.15), Bound(rule="approach", value=0.0,
                                                                  margin_s=0.2))
    first, last, found = bounds(seg, t, hand, robot, {})
    assert 2.0 <= t[first] <= 2.2                            # the reach, not the pick-up
    assert t[last] == pytest.approx(3.2, abs=0.02)           # arrival + 0.2 s
    assert found["closest_approach_m"] == pytest.approx(0.0, abs=1e-9)
    marks = {"go": (t > 1.5).astype(float), "stop": (t < 4).astype(float)}
    first, last, _ = bounds(Segment("hand", Bound(column="go"), Bound(column="stop")), t,
                            hand, robot, marks)
    assert (t[first], t[last]) == pytest.approx((1.51, 3.99))
    with pytest.raises(ValueError, match="segment.start: the hand never rests .* 5 m or more"):
        bounds(Segment("hand", Bound(rule="onset", value=0.1, distance_m=5.0)), t, hand, None,
               {})
    assert hand_speed(t, hand).max() == pytest.approx(0.6 * 1.875, rel=0.05)


def test_resample_hz_thins_to_every_other_row_and_the_loader_cuts(tmp_path):
    np.testing.assert_array_equal(thin(np.arange(12) / 120, 60.0), np.arange(0, 12, 2))
    t, hand, robot = _reach()
    rows = np.column_stack([hand, t > 2.5])
    _write(tmp_path / "a" / "1.csv", ["hx", "hy", "hz", "q", "mark"],
           [[*r[:3], 0.1, r[3]] for r in rows])
    spec = _spec(rate_hz=100, resample_hz=50,
                 segment={"start": {"column": "mark"}, "end": {"column": "mark"}})
    demo = load_trial(tmp_path / "a" / "1.csv", spec=spec, preprocess="none")
    assert demo.times[0] == 0.0 and demo.duration == pytest.approx(4.99 - 2.51, abs=1e-9)
    np.testing.assert_allclose(np.diff(demo.times), 0.02)
    assert demo.meta["report"]["segment"] == {"start_s": 2.51, "end_s": 4.99}


def test_a_signal_keeps_its_sign_unless_it_is_an_envelope():
    t = np.arange(200) / 100
    force = np.column_stack([-2.0 + 0.1 * np.sin(7 * t)])
    env, _, _ = preprocess_signal(t, force, "smooth", filter="envelope")
    low, _, _ = preprocess_signal(t, force, "smooth", filter="lowpass")
    raw, _, _ = preprocess_signal(t, force, "smooth", filter="none")
    assert (env > 1.5).all() and (low < -1.5).all()
    np.testing.assert_array_equal(raw, force)
    assert np.ptp(low) < np.ptp(force)                           # filtered, not raw
    with pytest.raises(ValueError, match=r"filter: expected one of \['envelope', 'lowpass'"):
        preprocess_signal(t, force, "smooth", filter="rectify")


def test_the_spec_chooses_a_signal_modalitys_preprocessing(tmp_path):
    t = np.arange(100) / 50
    _write(tmp_path / "a" / "1.csv", ["t", "hx", "hy", "hz", "q", "f"],
           [[ti, ti, 0, 0, 0.1, -3 + np.sin(5 * ti)] for ti in t])
    got = {}
    for how in ("envelope", "lowpass", "none"):
        spec = _spec(time="t", observe=["f"], modalities={
            "hand": HAND, "f": {"columns": ["f"], "kind": "signal", "preprocess": how}})
        got[how] = load_trial(tmp_path / "a" / "1.csv", spec=spec).human[:, 0]
    assert (got["envelope"] > 0).all() and (got["lowpass"] < 0).all()
    np.testing.assert_allclose(got["none"], -3 + np.sin(5 * t))
    assert _spec().layout.signal_filter("emg") == "envelope"     # EMG's default


def test_a_modalitys_own_frame_and_units_override_the_global_ones(tmp_path):
    _write(tmp_path / "a" / "1.csv", ["t", "hx", "hy", "hz", "wx", "wy", "wz", "q"],
           [[0.1 * i, i, 100, 0, 10, i, 0, 0.1] for i in range(4)])
    spec = _spec(time="t", units="cm", frame={"yaw": 90}, observe=["hand", "wrist"],
                 modalities={"hand": {**HAND, "units": "mm",
                                      "frame": {"up": "y", "translation": [1, 0, 0]}},
                             "wrist": {"columns": ["wx", "wy", "wz"]}})
    demo = load_trial(tmp_path / "a" / "1.csv", spec=spec, preprocess="none")
    np.testing.assert_allclose(demo.human[0, :3], [1, 0, 0.1], atol=1e-12)   # mm, y up
    np.testing.assert_allclose(demo.human[0, 3:], [0, 0.1, 0], atol=1e-12)   # cm, yaw 90


def test_part_files_are_one_per_part_in_the_specs_order_or_none(tmp_path):
    spec = _spec(rate_hz=5, files={"r": "arm.csv", "h": "*_hand.csv"}, robot=["r.j"],
                 modalities={"hand": {"columns": ["h.x", "h.y", "h.z"]}})
    _write(tmp_path / "t" / "a_hand.csv", ["x", "y", "z"], [[0, 0, 0]])
    _write(tmp_path / "t" / "arm.csv", ["j"], [[0]])
    assert part_files(tmp_path / "t", spec) == [tmp_path / "t" / "arm.csv",
                                                tmp_path / "t" / "a_hand.csv"]
    assert part_files(tmp_path / "t" / "arm.csv", spec) is None          # not a folder
    _write(tmp_path / "t" / "b_hand.csv", ["x", "y", "z"], [[0, 0, 0]])
    assert part_files(tmp_path / "t", spec) is None                      # two match 'h'
    (tmp_path / "t" / "arm.csv").unlink()
    assert part_files(tmp_path / "t", spec) is None                      # none match 'r'
