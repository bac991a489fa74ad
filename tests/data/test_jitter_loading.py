"""The loaders measure each position modality's raw jitter (issue 28 item 4): on sets with a
known 1 mm and 20 mm of tracker noise, what ``Demonstration.jitter``, ``data summary``'s
floor report and a fit with ``jitter_floor`` see."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
import yaml

from sandbox.core import IProMP
from sandbox.data.noisefloor import floor_summary
from sandbox.data.recorded import load_recorded
from sandbox.data.spec import DataSpec
from tests.commands.taskspace_data import GOALS, SPEC, trial


def noisy_set(root: Path, sigma: float, n_per_task: int = 5) -> list:
    rng = np.random.default_rng(0)
    for task in GOALS:
        (root / task).mkdir(parents=True, exist_ok=True)
        for i in range(n_per_task):
            np.savetxt(root / task / f"{i}.csv", trial(task, rng, jitter=sigma), delimiter=",",
                       header="t,hx,hy,hz,rx,ry,rz", comments="", fmt="%.6f")
    with warnings.catch_warnings():
        warnings.simplefilter("error")                     # no trial is skipped
        demos, skipped = load_recorded(root, spec=DataSpec.from_dict(yaml.safe_load(SPEC)))
    assert not skipped
    return demos


@pytest.mark.parametrize("sigma", [0.001, 0.02])
def test_a_known_tracker_jitter_is_what_the_loader_measures(tmp_path, sigma):
    demos = noisy_set(tmp_path, sigma)
    assert np.median([d.jitter["hand"] for d in demos]) == pytest.approx(sigma, rel=0.1)
    report = floor_summary(demos, jitter_floor=3.0, noise_floor=0.002)["hand"]
    assert report["jitter_m"] == pytest.approx(sigma, rel=0.1)
    assert report["floor_m"] == pytest.approx(max(0.002, 3 * sigma), rel=0.1)
    model = IProMP(n_basis=11, jitter_floor=3.0, noise_floor=0.002).fit(demos)  # raw jitter
    assert model.floors_used == pytest.approx([report["floor_m"]] * 3)
    default = floor_summary(demos)["hand"]["floor_m"]               # max(2 cm, 15 x jitter)
    assert default == pytest.approx(max(0.02, 15 * report["jitter_m"]))
    assert IProMP(n_basis=11).fit(demos).floors_used == pytest.approx([default] * 3)
    assert floor_summary(demos, jitter_floor=None)["hand"]["floor_m"] == 0.02


def test_zero_rows_re_sent_frames_and_a_jump_do_not_inflate_it(tmp_path):
    rng = np.random.default_rng(3)
    rows = trial("left", rng, jitter=0.001)
    rows[10:14, 1:4] = 0.0                                 # the tracker lost the hand
    rows[40::3, 1:4] = rows[39:-1:3, 1:4]                  # re-sent frames
    rows[80:83, 1:4] += 0.15                               # a 15 cm jump
    (tmp_path / "left").mkdir()
    np.savetxt(tmp_path / "left" / "0.csv", rows, delimiter=",", comments="", fmt="%.6f",
               header="t,hx,hy,hz,rx,ry,rz")
    demos, _ = load_recorded(tmp_path, spec=DataSpec.from_dict(yaml.safe_load(SPEC)))
    assert demos[0].jitter["hand"] == pytest.approx(0.001, rel=0.2)
