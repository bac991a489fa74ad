import json
from pathlib import Path

import numpy as np
import pytest

from sandbox.core.io import FORMAT_VERSION
from sandbox.core.model import IProMP
from sandbox.core.predictor import DynamicPredictor

from . import synth


@pytest.fixture(scope="module")
def model():
    return IProMP(n_basis=9, priors={"task0": 2, "task1": 1}).fit(
        synth.demos(np.random.default_rng(0), n_per_task=5))


def test_round_trip_predicts_identically(model, tmp_path):
    path = tmp_path / "model.npz"
    model.save(path)
    loaded = IProMP.load(path)
    assert loaded.tasks == model.tasks
    np.testing.assert_array_equal(loaded.priors, model.priors)
    np.testing.assert_array_equal(loaded.noise, model.noise)
    demo = synth.replay(1, 2.0)
    a, b = DynamicPredictor(model), DynamicPredictor(loaded)
    for t, y in zip(demo.times, demo.human):
        a.observe(t, y)
        b.observe(t, y)
    np.testing.assert_array_equal(a.command(1.9)[0], b.command(1.9)[0])


def test_file_holds_no_pickle(model, tmp_path):
    path = tmp_path / "model.npz"
    model.save(path)
    with np.load(path, allow_pickle=False) as data:
        meta = json.loads(str(data["metadata"]))
    assert meta["format_version"] == FORMAT_VERSION


def test_refuses_bad_files(model, tmp_path):
    good = tmp_path / "good.npz"
    model.save(good)
    raw = good.read_bytes()
    (tmp_path / "truncated.npz").write_bytes(raw[: len(raw) // 2])
    (tmp_path / "garbage.npz").write_bytes(b"not a zip file at all")
    np.savez(tmp_path / "foreign.npz", x=np.arange(3))
    with np.load(good) as data:
        arrays = {k: data[k] for k in data.files}
    meta = json.loads(str(arrays["metadata"]))
    meta["format_version"] = 999
    np.savez(tmp_path / "future.npz", **{**arrays, "metadata": np.array(json.dumps(meta))})
    meta["format_version"] = FORMAT_VERSION
    meta["format"] = "someone-else"
    np.savez(tmp_path / "other.npz", **{**arrays, "metadata": np.array(json.dumps(meta))})
    arrays["task0_factor"] = arrays["task0_factor"][:5]
    np.savez(tmp_path / "broken.npz", **arrays)
    cases = {"truncated": "corrupt", "garbage": "corrupt", "foreign": "no metadata",
             "future": "version 999", "other": "format", "broken": "inconsistent",
             "missing": "existing"}
    for name, message in cases.items():
        with pytest.raises(ValueError, match=message):
            IProMP.load(tmp_path / f"{name}.npz")


def test_unfitted_model_cannot_be_saved(tmp_path):
    with pytest.raises(RuntimeError, match="not fitted"):
        IProMP().save(tmp_path / "x.npz")


def test_multimodal_round_trip_keeps_modalities_scale_and_floors(tmp_path):
    demos = synth.multimodal(np.random.default_rng(1), n_per_task=5)
    model = IProMP(n_basis=9, noise_floors={"arm": 0.03}, signal_floor=0.2).fit(demos[1:])
    model.save(tmp_path / "m.npz")
    loaded = IProMP.load(tmp_path / "m.npz")
    assert loaded.modalities == model.modalities
    np.testing.assert_array_equal(loaded.scale, model.scale)
    assert (loaded.noise_floors, loaded.signal_floor, loaded.settle_tol) == (
        {"arm": 0.03}, 0.2, model.settle_tol)
    a = DynamicPredictor(model, observe=["emg", "hand"])
    b = DynamicPredictor(loaded, observe=["emg", "hand"])
    for t, y in zip(demos[0].times, demos[0].human):
        a.observe(t, np.r_[y[9:], y[:3]])
        b.observe(t, np.r_[y[9:], y[:3]])
    np.testing.assert_array_equal(a.command(1.5)[0], b.command(1.5)[0])
    assert a.task_posterior == b.task_posterior


def test_format_1_files_still_load():
    """tests/core/data/model_v1.npz was written by package 0.1.0 (format version 1)."""
    path = Path(__file__).parent / "data" / "model_v1.npz"
    with np.load(path) as data:
        assert json.loads(str(data["metadata"]))["format_version"] == 1
        factor = data["task1_factor"]
    model = IProMP.load(path)
    assert model.modality_names == ("hand",)
    assert model.human_names == ("human_0", "human_1", "human_2")
    np.testing.assert_array_equal(model.scale, 1.0)
    np.testing.assert_array_equal(model.task_models[1].weights.factor, factor)
    np.testing.assert_allclose(model.priors, [2 / 3, 1 / 3])
    pred = DynamicPredictor(model, dow_t=0.5)
    demo = synth.replay(1, 2.0)
    for t, y in zip(demo.times, demo.human):
        pred.observe(t, y)
    assert pred.task == "task1"


def test_only_declared_members_are_read(model, tmp_path):
    """An archive with a huge extra member is refused or loaded without reading it."""
    good = tmp_path / "good.npz"
    model.save(good)
    with np.load(good) as data:
        arrays = {k: data[k] for k in data.files}
    np.savez_compressed(tmp_path / "extra.npz", **arrays, junk=np.zeros(50_000_000, np.uint8))
    loaded = IProMP.load(tmp_path / "extra.npz")
    assert loaded.tasks == model.tasks
    del arrays["task1_reg"]
    np.savez(tmp_path / "lacking.npz", **arrays)
    with pytest.raises(ValueError, match=r"lacks \['task1_reg'\]"):
        IProMP.load(tmp_path / "lacking.npz")
