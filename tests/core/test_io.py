import json

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
