"""Property-based tests of the core's public entries (issue 13, item 9).

Whatever they are given, :meth:`IProMP.fit`, the predictors (constructor,
``observe``, ``update``, ``command``) and :meth:`IProMP.load` raise only
``ValueError`` (``RuntimeError`` for a call out of order: ``prediction()``
before the first update), and what they return (commands, posteriors, plans,
fitted arrays) is never NaN or infinite. The examples are derandomised, so a
run is reproducible.
"""

import io
import json
import os
import tempfile
import zipfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from sandbox.core.model import IProMP
from sandbox.core.predictor import DynamicPredictor, StaticPredictor

from . import synth

#: Examples per property test; ``SANDBOX_FUZZ_EXAMPLES`` sets them all for a longer campaign.
_CAMPAIGN = int(os.environ.get("SANDBOX_FUZZ_EXAMPLES", "0"))


def examples(n: int) -> int:
    """``n`` examples in the suite, or the campaign's number."""
    return _CAMPAIGN or n


SETTINGS = settings(deadline=None, derandomize=True, database=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
MODEL = IProMP(n_basis=7).fit(synth.demos(np.random.default_rng(0), n_per_task=4))
HAND = np.array([1.0, 0.0, 0.2])

#: Short strings over a fixed alphabet (no Unicode database to build: fast from cold).
TEXT = st.text(alphabet="ab1 ,.-\u00e9\u2603", max_size=4)
#: Anything a careless caller might pass where a number, a flag or a name is expected.
JUNK = st.one_of(
    st.none(), st.booleans(), TEXT, st.integers(-(10**30), 10**30),
    st.just(10**400), st.floats(allow_nan=True, allow_infinity=True),
    st.lists(st.floats(-10, 10), max_size=3), st.complex_numbers(max_magnitude=5),
    st.dictionaries(TEXT, st.integers(), max_size=2),
)
NUMBER = st.one_of(st.floats(1e-3, 1e3), st.integers(-3, 2000), JUNK)


def _finite(*arrays) -> bool:
    return all(np.all(np.isfinite(np.asarray(a, dtype=np.float64))) for a in arrays)


def _check_outputs(pred, t: float = 1.0) -> None:
    """Commands, plan and posterior finite; the posterior a probability vector."""
    mean, cov = pred.command(t)
    knots, means, covs = pred.plan()
    post = np.array(list(pred.task_posterior.values()))
    assert _finite(mean, cov, knots, means, covs, post, pred.duration, pred.alpha)
    assert np.all(post >= 0) and abs(post.sum() - 1) < 1e-9
    for u in pred.updates:
        assert _finite(u.task_posterior, u.alphas, u.durations, u.log_likelihood, u.jump)


# ------------------------------------------------------------- predictors
OPTIONS = ["subsample", "n_candidates", "width", "refine_steps", "dt", "blend_rate",
           "blend_delay", "blend", "horizon", "incremental", "until_end", "end_prob",
           "likelihood", "max_time", "observe", "dow_t", "window"]
OPTION_VALUES = st.one_of(NUMBER, st.sampled_from(["joint", "marginal", "all", "latest",
                                                   "hand", "emg", True, False]))


@settings(SETTINGS, max_examples=examples(80))
@given(st.dictionaries(st.sampled_from(OPTIONS), OPTION_VALUES, max_size=3))
def test_dynamic_predictor_options(options):
    try:
        pred = DynamicPredictor(MODEL, **options)
    except ValueError:
        return
    _check_outputs(pred)


@settings(SETTINGS, max_examples=examples(60))
@given(st.sampled_from(["ratio", "expected_duration", "subsample", "n_candidates"]), NUMBER)
def test_static_predictor_options(name, value):
    try:
        pred = StaticPredictor(MODEL, **{name: value})
    except ValueError:
        return
    _check_outputs(pred)


ROW = st.one_of(
    st.tuples(*[st.floats(-0.4, 0.4)] * 3).map(lambda d: HAND + np.array(d)),   # plausible
    st.lists(st.floats(allow_nan=True, allow_infinity=True), min_size=3, max_size=3),
    st.lists(st.sampled_from([1e153, -1e300, 1e-300, np.nan, 50.0, 0.0]), min_size=3,
             max_size=3),
    st.dictionaries(st.sampled_from(["hand", "arm"]), st.lists(st.floats(-2, 2), max_size=4),
                    max_size=2),
    JUNK,
)
DELTA = st.one_of(st.floats(0.0, 0.3), st.floats(-1.0, 2e9), st.just(np.nan), JUNK)
STEP = st.one_of(st.tuples(st.just("observe"), DELTA, ROW),
                 st.tuples(st.just("update"), st.one_of(st.none(), DELTA)),
                 st.tuples(st.just("command"), DELTA))


def _run(pred, steps) -> float:
    """Apply the steps, each from the last time reached; return that time."""
    now = 0.0
    for op, delta, *row in steps:
        t = now + delta if isinstance(delta, float) else delta
        try:
            if op == "observe":
                pred.observe(t, row[0])
            elif op == "update":
                pred.update(t)
            else:
                mean, cov = pred.command(t)
                assert _finite(mean, cov)
        except ValueError:
            continue
        if op != "command" and t is not None:
            now = max(now, float(t))
    return now


@settings(SETTINGS, max_examples=examples(40))
@given(st.lists(STEP, max_size=25), st.sampled_from(["dynamic", "static", "latest",
                                                     "marginal"]))
def test_predictors_observe_and_update(steps, kind):
    pred = {"dynamic": lambda: DynamicPredictor(MODEL, dow_t=0.1, subsample=1),
            "latest": lambda: DynamicPredictor(MODEL, dow_t=0.1, window="latest"),
            "marginal": lambda: DynamicPredictor(MODEL, dow_t=0.2, likelihood="marginal"),
            "static": lambda: StaticPredictor(MODEL, ratio=0.2, subsample=1)}[kind]()
    now = _run(pred, steps)
    _check_outputs(pred, now)
    if now > pred.max_time - 1.0:
        return
    demo = synth.replay(0, 0.6, rate=50.0)   # it still predicts from sound observations
    for t, y in zip(now + 0.01 + demo.times, demo.human):
        pred.observe(t, y)
    _check_outputs(pred, now + 0.6)
    if not pred.updates:
        with pytest.raises(RuntimeError):
            pred.prediction([now])


# -------------------------------------------------------------------- fit
@st.composite
def demo_sets(draw):
    n_tasks, P, Q = draw(st.integers(1, 2)), draw(st.integers(0, 3)), draw(st.integers(0, 2))
    scale = draw(st.sampled_from([1.0, 1.0, 1e3, 1e9, 1e-6]))
    rng = np.random.default_rng(draw(st.integers(0, 2**16)))
    wild = draw(st.sampled_from([None, np.nan, np.inf, 1e153, 1e10, 0.0]))
    demos = []
    for k in range(n_tasks):
        for _ in range(draw(st.integers(1, 3))):
            T = draw(st.integers(1, 25))
            times = scale * np.cumsum(rng.uniform(0.0 if wild == 0.0 else 0.01, 0.1, T))
            human = rng.normal(0, 1, (T, P))
            robot = rng.normal(0, 1, (T, Q))
            if wild is not None and T > 2:
                (human if draw(st.booleans()) else robot)[rng.integers(T), 0:1] = wild
            demos.append(synth.Demo(times, human, robot, draw(st.sampled_from(
                [f"task{k}", f"task{k}", "", None, 3]))))
    return demos


@settings(SETTINGS, max_examples=examples(80))
@given(demo_sets(), st.sampled_from([5, 9]))
def test_fit_any_demonstrations(demos, n_basis):
    try:
        model = IProMP(n_basis=n_basis).fit(demos)
    except ValueError:
        return
    assert _finite(model.noise, model.scale, model.priors)
    for task in model.task_models:
        assert _finite(task.weights.mean, task.weights.factor, task.weights.reg,
                       task.nominal_duration, task.alpha_std)
    try:
        pred = DynamicPredictor(model, dow_t=0.1)
    except ValueError:
        return
    for t, y in zip(demos[0].times, demos[0].human):
        try:
            pred.observe(t, y)
        except ValueError:
            pass
    _check_outputs(pred)


# ------------------------------------------------------------------- load
def _saved_members() -> dict[str, bytes]:
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "model.npz"
        MODEL.save(path)
        with zipfile.ZipFile(path) as z:
            return {n: z.read(n) for n in z.namelist()}


MEMBERS = _saved_members()
META = json.loads(str(np.load(io.BytesIO(MEMBERS["metadata.npy"]))))
JSON = st.recursive(st.one_of(st.none(), st.booleans(), st.integers(-(10**20), 10**20),
                              st.floats(allow_nan=True, allow_infinity=True), TEXT),
                    lambda inner: st.one_of(st.lists(inner, max_size=3),
                                            st.dictionaries(TEXT, inner,
                                                            max_size=3)),
                    max_leaves=6)


def _paths(value, prefix=()):
    """Every path to a value inside the metadata."""
    yield prefix
    if isinstance(value, dict):
        for k, v in value.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            yield from _paths(v, prefix + (i,))


PATHS = [p for p in _paths(META) if p]


def _replace(meta, path, value):
    out = json.loads(json.dumps(meta))
    node = out
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    return out


def _npy(array) -> bytes:
    out = io.BytesIO()
    np.save(out, array, allow_pickle=True)
    return out.getvalue()


ARRAY = st.one_of(
    st.lists(st.floats(allow_nan=True, allow_infinity=True), max_size=6).map(np.array),
    st.sampled_from([np.zeros((3, 3)), np.ones(3), -np.ones(3), np.array([1e-300] * 3),
                     np.array([1e300] * 3), np.array(["a", "b", "c"]),
                     np.array([None, {}, 1], dtype=object), np.ones(3, complex),
                     np.zeros(0), np.ones(3, bool)]),
)
MUTATION = st.one_of(
    st.tuples(st.just("metadata"), st.sampled_from(PATHS), JSON),
    st.tuples(st.just("scale"), st.sampled_from(sorted(n[:-4] for n in MEMBERS
                                                       if n != "metadata.npy")),
              st.sampled_from([0.0, -1.0, 1e-30, 1e-12, 1e12, 1e40, np.nan])),
    st.tuples(st.just("array"), st.sampled_from(sorted(n[:-4] for n in MEMBERS)), ARRAY),
    st.tuples(st.just("bytes"), st.integers(0, 10**6), st.integers(0, 255)),
    st.tuples(st.just("truncate"), st.integers(0, 10**6), st.just(0)),
    st.tuples(st.just("drop"), st.sampled_from(sorted(MEMBERS)), st.just(0)),
)


def _mutated(kind, where, what) -> bytes:
    members = dict(MEMBERS)
    if kind == "metadata":
        members["metadata.npy"] = _npy(np.array(json.dumps(_replace(META, where, what))))
    elif kind == "scale":
        arr = np.load(io.BytesIO(members[f"{where}.npy"]))
        members[f"{where}.npy"] = _npy(arr * what)
    elif kind == "array":
        members[f"{where}.npy"] = _npy(what)
    elif kind == "drop":
        del members[where]
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w") as z:
        for name, data in members.items():
            z.writestr(name, data)
    raw = bytearray(out.getvalue())
    if kind == "bytes":
        raw[where % len(raw)] = what
    elif kind == "truncate":
        raw = raw[: where % len(raw)]
    return bytes(raw)


@settings(SETTINGS, max_examples=examples(100))
@given(MUTATION)
def test_load_mutated_model_files(tmp_path_factory, mutation):
    path = tmp_path_factory.getbasetemp() / "mutated.npz"
    path.write_bytes(_mutated(*mutation))
    try:
        model = IProMP.load(path)
    except ValueError as error:
        assert "pickle" not in str(error)
        return
    pred = DynamicPredictor(model, dow_t=0.2)   # a file that loads works (issue 26 item 1)
    demo = synth.replay(1, 1.5)
    for t, y in zip(demo.times, demo.human):
        pred.observe(t, y)
    _check_outputs(pred, 1.5)
