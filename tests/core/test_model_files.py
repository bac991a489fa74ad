"""Model files that loaded and then failed late (issue 26, item 1).

:meth:`IProMP.load` checks everything the predictors rely on: a file it
accepts gives predictors that run, and every other file is one ``ValueError``
naming the file, the member and what was expected. Regression tests name the
file that loaded before; the property test mutates a fitted model's file in
ways a fit cannot produce and asserts one of the two outcomes, and that loading
never changes anything on disk.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from sandbox.cli import main
from sandbox.core.fitting import check_speed_spread
from sandbox.core.limits import MAX_ALPHA_STD
from sandbox.core.model import IProMP
from sandbox.core.predictor import DynamicPredictor, StaticPredictor
from tests._hypothesis import property_settings

from . import synth

MODEL = IProMP(n_basis=7).fit(synth.demos(np.random.default_rng(0), n_per_task=4))


def _content(model: IProMP, folder) -> tuple[dict, dict]:
    """A saved model's members as arrays and its metadata as a dict."""
    path = folder / "fitted.npz"
    model.save(path)
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    return arrays, json.loads(str(arrays["metadata"]))


@pytest.fixture(scope="module")
def content(tmp_path_factory):
    return _content(MODEL, tmp_path_factory.mktemp("model"))


def _write(path, arrays, meta):
    np.savez(path, **{**arrays, "metadata": np.array(json.dumps(meta))})
    return path


def _changed(meta, **task0):
    out = json.loads(json.dumps(meta))
    out["tasks"][0].update(task0)
    return out


def _run(model: IProMP) -> None:
    """Both predictors over a replayed motion: commands, plan and posterior finite."""
    demo = synth.replay(1, 1.5)
    for pred in (DynamicPredictor(model, dow_t=0.2), StaticPredictor(model)):
        for t, y in zip(demo.times[::2], demo.human[::2]):
            pred.command(t)
            pred.observe(t, y)
        mean, cov = pred.command(1.5)
        _, means, covs = pred.plan()
        post = np.array(list(pred.task_posterior.values()))
        for a in (mean, cov, means, covs, post):
            assert np.all(np.isfinite(a))
        assert abs(post.sum() - 1) < 1e-9


# ------------------------------------------------------------ the reproducers
def test_a_factor_without_columns_is_refused(content, tmp_path):
    """issue 26 item 1: a task covariance factor of zero columns loaded, then the predictor
    failed with "cannot reshape array of size 0 into shape (3,0)"."""
    arrays, meta = content
    arrays = {**arrays, "task0_factor": arrays["task0_factor"][:, :0]}
    with pytest.raises(ValueError, match=r"bad\.npz.*'task0_factor': expected a covariance "
                                         r"factor of rank 1 to 3 .* got 0 columns"):
        IProMP.load(_write(tmp_path / "bad.npz", arrays, meta))


def test_a_speed_spread_no_fit_makes_is_refused(content, tmp_path):
    """issue 26 item 1: metadata alpha_std 1e6 loaded, then the predictor failed building its
    speed lattice ("more candidates than limits.MAX_LATTICE_FLOATS")."""
    arrays, meta = content
    with pytest.raises(ValueError, match=r"bad\.npz.*task 'task0' alpha_std: expected a "
                                         r"speed-factor spread in \[0\.02, 2\].*got 1e\+06"):
        IProMP.load(_write(tmp_path / "bad.npz", arrays, _changed(meta, alpha_std=1e6)))


# ------------------------------------------------ each thing the predictor needs
def _factor(arrays, columns):
    return {**arrays, "task0_factor": columns(arrays["task0_factor"])}


REFUSED = {
    "factor rank above n_demos - 1": (lambda a, m: (_factor(a, lambda f: np.hstack([f, f[:, :1]])),
                                                     m), "rank 1 to 3"),
    "factor all zeros": (lambda a, m: (_factor(a, np.zeros_like), m), "all zeros"),
    "one demo": (lambda a, m: (a, _changed(m, n_demos=1)), "n_demos: expected an integer >= 2"),
    "alpha_mean not 1": (lambda a, m: (a, _changed(m, alpha_mean=1.5)), "alpha_mean: expected 1"),
    "alpha_std below min_alpha_std": (lambda a, m: (a, _changed(m, alpha_std=1e-6)),
                                      "alpha_std: expected"),
    "alpha_std of many demos beyond the limit": (
        lambda a, m: (a, _changed(m, alpha_std=50.0, n_demos=10**6)), "MAX_ALPHA_STD 10"),
    "nominal duration below a sample": (lambda a, m: (a, _changed(m, nominal_duration=1e-6)),
                                        "nominal_duration: expected at least"),
    "human regulariser over noise beyond MAX_KAPPA": (
        lambda a, m: ({**a, "task0_reg": a["task0_reg"] * 1e20}, m), "MAX_KAPPA"),
    "basis width near the smallest float": (
        lambda a, m: (a, {**m, "basis": {**m["basis"], "width": 1e-320}}), "width"),
    "min_alpha_std no fit accepts": (
        lambda a, m: (a, {**m, "hyperparameters": {**m["hyperparameters"],
                                                   "min_alpha_std": 1e6}}), "min_alpha_std"),
    "priors not summing to 1": (lambda a, m: (a, _changed(m, prior=0.9)), "summing to 1"),
    "modalities not adding up to n_human": (
        lambda a, m: (a, {**m, "n_human": 2}), "modalities: expected 2 human dims"),
}


@pytest.mark.parametrize("name", list(REFUSED))
def test_what_the_predictor_relies_on_is_checked_at_load(content, tmp_path, name):
    arrays, meta = content
    change, message = REFUSED[name]
    arrays, meta = change(arrays, json.loads(json.dumps(meta)))
    path = _write(tmp_path / "bad.npz", arrays, meta)
    with pytest.raises(ValueError, match=message) as info:
        IProMP.load(path)
    assert type(info.value) is ValueError and "bad.npz" in str(info.value)
    assert "\n" not in str(info.value)


def test_a_fit_refuses_durations_no_speed_prior_covers():
    """The bound the loader holds files to, held by the fit too (limits.MAX_ALPHA_STD)."""
    durations = np.array([0.1] * 200 + [400.0])
    spread = float(np.std(durations / durations.mean(), ddof=1))
    assert spread > MAX_ALPHA_STD
    with pytest.raises(ValueError, match="MAX_ALPHA_STD"):
        check_speed_spread("give", spread, durations)


def test_a_fitted_model_and_a_recorded_one_still_load(content, tmp_path):
    arrays, meta = content
    _run(IProMP.load(_write(tmp_path / "same.npz", arrays, meta)))
    from pathlib import Path

    _run(IProMP.load(Path(__file__).parent / "data" / "model_v1.npz"))


@pytest.mark.parametrize("case", ["zero columns", "alpha_std 1e6"])
def test_the_command_line_refuses_them_in_one_line(content, tmp_path, capsys, case):
    arrays, meta = content
    if case == "zero columns":
        arrays = {**arrays, "task0_factor": arrays["task0_factor"][:, :0]}
    else:
        meta = _changed(meta, alpha_std=1e6)
    path = _write(tmp_path / "bad.npz", arrays, meta)
    out = tmp_path / "report.json"
    code = main(["evaluate", "--model", str(path), "--data", "synthetic:two_task",
                 "--no-progress", "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "Traceback" not in err
    assert "bad.npz" in err and not out.exists()


# ------------------------------------------------------------ the property test
#: Members and metadata numbers a mutation may touch.
NUMBERS = st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                    st.sampled_from([0.0, -1.0, 1e-320, 1e-12, 1e-6, 0.5, 1.0, 1 + 1e-12, 3.0,
                                     1e6, 1e30, 1e300]),
                    st.integers(-3, 10**7))
TASK_KEYS = ["nominal_duration", "alpha_mean", "alpha_std", "n_demos", "prior"]
HYPER_KEYS = ["regularizer", "noise_scale", "noise_floor", "signal_floor", "settle_tol",
              "arrive_tol", "min_alpha_std", "ridge"]
MUTATION = st.one_of(
    st.tuples(st.just("task"), st.sampled_from(TASK_KEYS), NUMBERS),
    st.tuples(st.just("hyper"), st.sampled_from(HYPER_KEYS), NUMBERS),
    st.tuples(st.just("basis"), st.sampled_from(["width", "margin", "n_basis"]), NUMBERS),
    st.tuples(st.just("count"), st.sampled_from(["n_human", "n_robot"]), st.integers(0, 12)),
    st.tuples(st.just("scale"), st.sampled_from(["noise", "task0_mean", "task0_factor",
                                                 "task0_reg", "task1_reg"]), NUMBERS),
    st.tuples(st.just("columns"), st.sampled_from(["task0_factor", "task1_factor"]),
              st.integers(0, 6)),
)


def _mutate(arrays: dict, meta: dict, kind: str, key: str, value):
    arrays, meta = dict(arrays), json.loads(json.dumps(meta))
    if kind == "task":
        meta["tasks"][0][key] = value
    elif kind == "hyper":
        meta["hyperparameters"][key] = value
    elif kind == "basis":
        meta["basis"][key] = value
    elif kind == "count":
        meta[key] = value
    elif kind == "scale":
        with np.errstate(all="ignore"):
            arrays[key] = arrays[key] * value
    else:                  # keep, drop or repeat the factor's columns
        f = arrays[key]
        arrays[key] = np.hstack([f, f, f])[:, :value]
    return arrays, meta


@property_settings(60)
@given(mutation=MUTATION)
def test_a_mutated_model_file_is_refused_or_works(content, tmp_path_factory, mutation):
    """Either one ValueError naming the file, or predictors that run and give finite
    outputs; the file itself, and its folder, are left as they were."""
    folder = tmp_path_factory.mktemp("mutated")
    path = _write(folder / "m.npz", *_mutate(*content, *mutation))
    before = path.read_bytes()
    try:
        model = IProMP.load(path)
    except ValueError as error:
        text = str(error)
        assert type(error) is ValueError and "m.npz" in text and "\n" not in text
        assert "pickle" not in text
    else:
        _run(model)
    assert path.read_bytes() == before and [p.name for p in folder.iterdir()] == ["m.npz"]
