"""The weight regulariser raised to the out-of-span variance (issue 21 item 4, ``span_reg``):
the variance's known answers, the regulariser it sets, the held-out choice, the model file."""

from __future__ import annotations

import json

import numpy as np
import pytest

from sandbox.core import IProMP, spanreg
from sandbox.core.spanreg import GRID, SPAN_NOTE, check_span_reg, out_of_span_variance
from tests.core.test_floorsearch import demos

OPTIONS = {"n_basis": 9, "settle_tol": None, "arrive_tol": None}


def test_the_out_of_span_variance_of_three_points():
    # Left out in turn, (0,0), (2,0), (0,2) leave (0,2), (-1,-1), (2,0) outside the
    # others' line: mean squares 2, 1, 2 per coordinate.
    x = {"a": np.array([[0.0, 0.0], [2.0, 0.0], [0.0, 2.0]])}
    assert out_of_span_variance(x, slice(0, 2)) == pytest.approx(5.0 / 3.0)
    assert out_of_span_variance({"a": x["a"][:2]}, slice(0, 2)) is None   # too few demos


def test_demos_in_their_span_have_none_and_departures_grow_it():
    def variance(departure):
        model = IProMP(span_reg=1.0, **OPTIONS).fit(demos(departure))
        return model.span_report["hand"]["variance"]

    assert variance(0.0) < 1e-12 < variance(0.005) < variance(0.05)


def test_the_regulariser_is_raised_to_the_factor_and_kept_per_modality():
    base = IProMP(**OPTIONS).fit(demos(0.05))
    none = IProMP(span_reg=0.0, **OPTIONS).fit(demos(0.05))
    raised = IProMP(span_reg=1.0, **OPTIONS).fit(demos(0.05))
    v = raised.span_report["hand"]["variance"]
    P = base.n_human
    for a, b, c in zip(base.task_models, none.task_models, raised.task_models):
        assert np.array_equal(a.weights.reg, b.weights.reg)          # factor 0: today's
        assert np.allclose(c.weights.reg[:P].mean(), max(v, a.weights.reg[:P].mean()))
        assert np.array_equal(c.weights.reg[P:], a.weights.reg[P:])   # robot's unchanged
        kappa = c.weights.reg[:P] / raised.noise
        assert np.allclose(kappa, kappa[0])                           # one kappa per modality
    assert base.span_report == {} and base.span_reg is None


def test_auto_takes_the_factor_of_the_best_held_out_score(monkeypatch):
    monkeypatch.setattr(spanreg, "GRID", (0.0, 0.1, 1.0))     # the full grid: same code, slower
    model = IProMP(span_reg="auto", **OPTIONS).fit(demos(0.05, n=4))
    entry = model.span_report["hand"]
    assert set(entry["scores"]) == {0.0, 0.1, 1.0} and len(GRID) == 6
    assert entry["factor"] == max(entry["scores"], key=entry["scores"].get)
    assert all(np.isfinite(s) and s <= 0 for s in entry["scores"].values())   # log p(k | y)


@pytest.mark.parametrize("bad", ["yes", -0.1, 11.0, True, [1.0]])
def test_a_bad_span_reg_is_refused(bad):
    with pytest.raises(ValueError, match="span_reg"):
        check_span_reg(bad)
    with pytest.raises(ValueError, match="span_reg"):
        IProMP(span_reg=bad)


def test_the_file_keeps_it_and_an_older_file_says_so(tmp_path):
    model = IProMP(span_reg=0.5, **OPTIONS).fit(demos(0.05))
    path = tmp_path / "m.npz"
    model.save(path)
    back = IProMP.load(path)
    assert back.span_reg == 0.5 and back.span_note is None
    assert back.span_report["hand"]["factor"] == 0.5
    for a, b in zip(model.task_models, back.task_models):
        assert np.array_equal(a.weights.reg, b.weights.reg)
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    meta = json.loads(str(arrays["metadata"]))
    del meta["hyperparameters"]["span_reg"], meta["span_used"]     # as written before it
    old = tmp_path / "old.npz"
    np.savez(old, **{**arrays, "metadata": np.array(json.dumps(meta))})
    loaded = IProMP.load(old)
    assert loaded.span_reg is None and loaded.span_note == SPAN_NOTE
    meta["span_used"] = {"hand": {"variance": -1.0, "factor": 1.0}}
    np.savez(old, **{**arrays, "metadata": np.array(json.dumps(meta))})
    with pytest.raises(ValueError, match="span_used"):
        IProMP.load(old)
