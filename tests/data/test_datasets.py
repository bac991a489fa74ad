"""Tests of sandbox.data.datasets: load_dataset dispatch and uniform resampling."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sandbox.data.datasets import load_dataset, resample_uniform, synthetic_names
from sandbox.data.demonstration import Demonstration
from sandbox.data.recorded import HUMAN_COLUMNS, ROBOT_COLUMNS


def write_trial(path: Path, n: int = 30, seed: int = 0) -> Path:
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 0.03
    hand = np.array([1.1, -0.1, 0.25]) + t[:, None] * [-0.2, 0.1, 0.0] + rng.normal(0, 1e-3, (n, 3))
    robot = 0.1 * np.arange(7) + t[:, None] * 0.05
    path.parent.mkdir(parents=True, exist_ok=True)
    lines = [",".join(["t", *HUMAN_COLUMNS, *ROBOT_COLUMNS])]
    lines += [",".join(f"{v:.6f}" for v in row) for row in np.column_stack([t, hand, robot])]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    for task in ("reach", "wave"):
        for i in range(3):
            write_trial(tmp_path / "set" / task / f"trial{i}.csv", seed=i)
    return tmp_path / "set"


def test_folder_spec_with_task_subset_and_n_per_task(folder):
    demos = load_dataset(folder, n_per_task=2, preprocess="none")
    assert [(d.task, Path(d.source).name) for d in demos] == [
        ("reach", "trial0.csv"), ("reach", "trial1.csv"),
        ("wave", "trial0.csv"), ("wave", "trial1.csv"),
    ]
    assert [d.task for d in load_dataset(str(folder), tasks=["wave"])] == ["wave"] * 3


def test_synthetic_spec_is_seeded():
    a = load_dataset("synthetic:two_task", seed=3, n_per_task=2)
    b = load_dataset("synthetic:two_task", seed=3, n_per_task=2)
    c = load_dataset("synthetic:two_task", seed=4, n_per_task=2)
    assert len(a) == 4 and {d.task for d in a} == {"left", "right"}
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x.human, y.human)
    assert not np.allclose(a[0].human[:10], c[0].human[:10])


def test_synthetic_spec_is_preprocessed_unless_none():
    raw = load_dataset("synthetic:two_task", n_per_task=2, preprocess="none")
    smooth = load_dataset("synthetic:two_task", n_per_task=2, preprocess="smooth")
    assert "report" not in raw[0].meta
    assert smooth[0].meta["report"]["preprocess"] == "smooth"
    np.testing.assert_array_equal(smooth[0].times, raw[0].times)
    np.testing.assert_array_equal(smooth[0].robot, raw[0].robot)
    # smoothing removes part of the white noise the generator adds
    assert np.std(np.diff(smooth[0].human, 2, axis=0)) < np.std(np.diff(raw[0].human, 2, axis=0))


def test_synthetic_task_subset():
    demos = load_dataset("synthetic:two_task", n_per_task=2, tasks=["right"], preprocess="none")
    assert [d.task for d in demos] == ["right", "right"]
    with pytest.raises(ValueError, match=r"expected some of \['left', 'right'\]"):
        load_dataset("synthetic:two_task", n_per_task=2, tasks=["up"])


@pytest.mark.parametrize("spec", ["nowhere/at/all", "synthetic:nope", "synthetic:", 42])
def test_unknown_spec_lists_the_options(spec):
    with pytest.raises(ValueError, match="synthetic:two_task") as info:
        load_dataset(spec)
    assert "folder" in str(info.value)


@pytest.mark.parametrize(
    "kwargs, match",
    [({"preprocess": "kalman"}, "preprocess"), ({"n_per_task": 0}, "n_per_task"),
     ({"rate_hz": -1.0}, "rate_hz")],
)
def test_bad_options_are_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        load_dataset("synthetic:two_task", **kwargs)


def test_synthetic_names_include_the_minimal_generator():
    assert "two_task" in synthetic_names()


def linear_demo(times, human=None) -> Demonstration:
    times = np.asarray(times, dtype=float)
    if human is None:
        human = np.column_stack([times, 2 * times, 0 * times + 1])
    robot = np.column_stack([3 * times] * 7)
    return Demonstration(times=times, human=human, robot=robot, task="t")


def test_resample_uniform_keeps_span_and_interpolates_linear_signals():
    demo = linear_demo([0.1, 0.13, 0.2, 0.41, 0.5, 0.71, 0.9])  # gaps < 0.25 s
    out = resample_uniform(demo, 50.0)
    assert out.times[0] == demo.times[0] and out.times[-1] == demo.times[-1]
    assert out.n_steps == 41
    np.testing.assert_allclose(np.diff(out.times), 0.02)
    np.testing.assert_allclose(out.human[:, 1], 2 * out.times)
    np.testing.assert_allclose(out.robot, 3 * np.tile(out.times[:, None], 7))
    assert out.meta["resampled_hz"] == 50.0


def test_resample_uniform_does_not_invent_across_long_gaps():
    t = np.linspace(0.0, 1.0, 101)
    human = np.column_stack([t, t, t])
    human[30:70] = np.nan  # a 0.41 s dropout
    human[80] = np.nan  # a short one
    out = resample_uniform(linear_demo(t, human), 100.0, max_gap_s=0.25)
    inside = (out.times > 0.29 + 1e-9) & (out.times < 0.70 - 1e-9)
    assert np.isnan(out.human[inside]).all()
    assert np.isfinite(out.human[~inside]).all()
    np.testing.assert_allclose(out.human[80], 0.8)


def test_load_dataset_rate_option(folder):
    demos = load_dataset(folder, rate_hz=20.0, preprocess="none")
    for d in demos:  # uniform; the step is duration / (n - 1), the nearest to 1 / rate_hz
        step = np.diff(d.times)
        np.testing.assert_allclose(step, step[0])
        assert abs(step[0] - 0.05) < 0.05 / (d.n_steps - 1)


def test_recorded_dataset_subset(recorded_dir):
    demos = load_dataset(recorded_dir, tasks=["screw_driver", "pencil_box"], n_per_task=3,
                         preprocess="causal")
    assert [d.task for d in demos] == ["screw_driver"] * 3 + ["pencil_box"] * 3
    assert all(d.meta["report"]["preprocess"] == "causal" for d in demos)


def test_importing_sandbox_data_stays_light():
    import subprocess
    import sys

    # filterpy (and the scipy.stats it imports) only once a HandFilter is made: the loader's
    # vectorised filter does not need it
    code = ("import sys, sandbox.data as d; heavy = [m for m in ('filterpy', 'scipy.stats', "
            "'pybullet', 'matplotlib', 'meshcat') if m in sys.modules]; assert not heavy, heavy; "
            "assert d.HandFilter.__name__ == 'HandFilter' and 'filterpy' not in sys.modules; "
            "d.HandFilter(3); assert 'filterpy' in sys.modules")
    subprocess.run([sys.executable, "-c", code], check=True)


def test_a_synthetic_set_takes_a_session_and_a_folder_or_minari_refuses_it(tmp_path):
    from sandbox.data.synthetic.session import draw_session

    demos = load_dataset("synthetic:objects", n_per_task=2, session=4, preprocess="none")
    assert all(d.meta["session"] == draw_session(4).to_dict() for d in demos)
    plain = load_dataset("synthetic:objects", n_per_task=2, preprocess="none")
    assert all("session" not in d.meta for d in plain)
    for data in (str(tmp_path), "minari:some-id"):
        with pytest.raises(ValueError, match="^session: only for synthetic:NAME data"):
            load_dataset(data, session=1)
    with pytest.raises(ValueError, match="^session: expected an integer >= 0"):
        load_dataset("synthetic:objects", session=-1)


def test_load_pair_passes_the_session_to_both_versions():
    from sandbox.eval.datasets import load_pair

    train, test, _ = load_pair("synthetic:objects", n_per_task=2, session=5)
    assert train and len(train) == len(test)
    assert {d.meta["session"]["seed"] for d in train + test} == {5}
