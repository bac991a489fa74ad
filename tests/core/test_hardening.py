"""Regression tests of issue 13 (hardening): each names the finding it pins.

Every one of them failed on the code before the fix (a ``MemoryError``, a
``TypeError``, a silently accepted input or a poisoned predictor).
"""

import json
import tempfile
import tracemalloc
import zipfile

import numpy as np
import pytest

from sandbox.core.model import IProMP
from sandbox.core.predictor import DynamicPredictor, StaticPredictor

from . import synth


@pytest.fixture(scope="module")
def demos():
    return synth.demos(np.random.default_rng(0), n_per_task=5)


@pytest.fixture(scope="module")
def model(demos):
    return IProMP(n_basis=9).fit(demos)


@pytest.fixture(scope="module")
def saved(model, tmp_path_factory):
    """The model's file: its members as arrays and its metadata as a dict."""
    path = tmp_path_factory.mktemp("model") / "model.npz"
    model.save(path)
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    return arrays, json.loads(str(arrays["metadata"]))


def _write(path, arrays, meta=None, compressed=False):
    if meta is not None:
        arrays = {**arrays, "metadata": np.array(json.dumps(meta))}
    (np.savez_compressed if compressed else np.savez)(path, **arrays)
    return path


def _messages(error: BaseException) -> str:
    out = []
    while error is not None:
        out.append(str(error))
        error = error.__cause__ or error.__context__
    return " | ".join(out)


# ----------------------------------------------------------------- finding 1
def test_fit_refuses_nanosecond_demos(demos):
    """issue 13 finding 1: IProMP.fit accepted demos stamped in nanoseconds, and
    DynamicPredictor(model) then tried to allocate 1.7 TiB (the prior plan at 0.01 s)."""
    ns = [synth.Demo(d.times * 1e9, d.human, d.robot, d.task) for d in demos]
    with pytest.raises(ValueError, match="looks like nanoseconds"):
        IProMP(n_basis=9).fit(ns)
    ms = [synth.Demo(d.times * 1e3, d.human, d.robot, d.task) for d in demos]
    with pytest.raises(ValueError, match="looks like milliseconds"):
        IProMP(n_basis=9).fit(ms)


def test_sizes_are_bounded_before_anything_is_allocated(model):
    """issue 13 finding 1 (and 8, ``fit --n-basis 200000``): n_basis, n_candidates and the
    plan's length were unbounded (a MemoryError or many gigabytes)."""
    with pytest.raises(ValueError, match="n_basis"):
        IProMP(n_basis=200_000)
    with pytest.raises(ValueError, match="n_candidates"):
        DynamicPredictor(model, n_candidates=10**7)
    with pytest.raises(ValueError, match=r"blend_rate: .*\(sandbox.limits\)"):   # issue 29
        DynamicPredictor(model, blend_rate=1e-9)
    for options in ({"dt": 1e-9}, {"horizon": 1e9}):
        with pytest.raises(ValueError, match="MAX_PLAN_STEPS"):
            DynamicPredictor(model, **options)


# ----------------------------------------------------------------- finding 3
def test_a_model_member_is_checked_before_it_is_read(saved, tmp_path):
    """issue 13 finding 3 (zip bomb): a small compressed file declaring a huge member was
    read in full (275 KB allocated 256 MB) before its shape was checked."""
    arrays, _ = saved
    path = _write(tmp_path / "bomb.npz", {**arrays, "noise": np.zeros(5_000_000)},
                  compressed=True)
    assert path.stat().st_size < 200_000
    tracemalloc.start()
    try:
        with pytest.raises(ValueError, match="noise"):
            IProMP.load(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 5_000_000


def test_a_declared_huge_shape_is_refused_without_allocating(saved, tmp_path):
    """issue 13 finding 3: a member whose header declares a huge shape gave MemoryError."""
    arrays, _ = saved
    path = _write(tmp_path / "model.npz", arrays)
    with zipfile.ZipFile(path) as z:
        members = {n: z.read(n) for n in z.namelist()}
    header = np.lib.format.header_data_from_array_1_0(np.zeros(1))
    header["shape"] = (10**12,)
    from io import BytesIO

    fake = BytesIO()
    np.lib.format.write_array_header_1_0(fake, header)
    members["task0_factor.npy"] = fake.getvalue() + b"\0" * 64
    with zipfile.ZipFile(path, "w") as z:
        for name, data in members.items():
            z.writestr(name, data)
    with pytest.raises(ValueError, match="task0_factor"):
        IProMP.load(path)


# ----------------------------------------------------------------- finding 4
@pytest.mark.parametrize("change, message", [
    ({"prior": 5.0}, "prior"),                     # priors [5, 5]: commands 10x too large
    ({"prior": float("nan")}, "prior"),            # NaN prior: NaN commands
    ({"alpha_mean": 0.0}, "alpha_mean"),           # alpha_mean = 0: NaN commands
    ({"alpha_std": -0.1}, "alpha_std"),
    ({"nominal_duration": 1e9}, "nominal_duration"),
])
def test_tampered_task_metadata_is_refused(saved, tmp_path, change, message):
    """issue 13 finding 4: priors [5, 5], a NaN prior or alpha_mean = 0 were accepted
    (commands 10x too large or NaN)."""
    arrays, meta = saved
    meta = json.loads(json.dumps(meta))
    for task in meta["tasks"]:
        task.update(change)
    with pytest.raises(ValueError, match=message):
        IProMP.load(_write(tmp_path / "m.npz", arrays, meta))


def _deep(meta):
    return "[" * 100_000 + "]" * 100_000


MALFORMED = {
    "deep JSON (RecursionError)": _deep,
    "JSON list": lambda m: [1, 2],
    "version as text": lambda m: {**m, "format_version": "2"},
    "version as bool": lambda m: {**m, "format_version": True},
    "n_basis as text": lambda m: {**m, "basis": {**m["basis"], "n_basis": "9"}},
    "basis as list": lambda m: {**m, "basis": [9]},
    "unknown basis key": lambda m: {**m, "basis": {**m["basis"], "centres": 3}},
    "tasks as dict": lambda m: {**m, "tasks": {"a": 1}},
    "task as text": lambda m: {**m, "tasks": ["task0"]},
    "task lacks a key": lambda m: {**m, "tasks": [{k: v for k, v in t.items() if k != "n_demos"}
                                                  for t in m["tasks"]]},
    "duration as text": lambda m: {**m, "tasks": [{**t, "nominal_duration": "2"}
                                                  for t in m["tasks"]]},
    "n_human as text": lambda m: {**m, "n_human": "3"},
    "n_robot huge": lambda m: {**m, "n_robot": 10**12},
    "hyperparameters as list": lambda m: {**m, "hyperparameters": [1]},
    "unknown hyperparameter": lambda m: {**m, "hyperparameters": {**m["hyperparameters"],
                                                                  "bogus": 1}},
    "regularizer as text": lambda m: {**m, "hyperparameters": {**m["hyperparameters"],
                                                               "regularizer": "x"}},
    "modality dims as number": lambda m: {**m, "modalities": [{**m["modalities"][0],
                                                               "dims": 3}]},
    "modalities as text": lambda m: {**m, "modalities": "hand"},
    "robot_names as number": lambda m: {**m, "robot_names": 7},
    "no metadata key": lambda m: {k: v for k, v in m.items() if k != "tasks"},
}


@pytest.mark.parametrize("name", list(MALFORMED))
def test_malformed_metadata_is_a_value_error(saved, tmp_path, name):
    """issue 13 finding 4: eleven malformed files raised TypeError, KeyError or
    RecursionError instead of one ValueError."""
    arrays, meta = saved
    changed = MALFORMED[name](json.loads(json.dumps(meta)))
    text = changed if isinstance(changed, str) else json.dumps(changed)
    path = _write(tmp_path / "m.npz", {**arrays, "metadata": np.array(text)})
    with pytest.raises(ValueError) as info:
        IProMP.load(path)
    assert type(info.value) is ValueError and "m.npz" in str(info.value)


@pytest.mark.parametrize("member", ["task0_reg", "noise", "task1_mean"])
def test_nan_or_non_positive_arrays_are_refused(saved, tmp_path, member):
    """issue 13 finding 4: NaN in an array or a zero regulariser/noise were loaded."""
    arrays, _ = saved
    for bad in (np.nan, 0.0):
        if member == "task1_mean" and bad == 0.0:
            continue
        values = arrays[member].copy()
        values[0] = bad
        with pytest.raises(ValueError, match=member.split("_")[0]):
            IProMP.load(_write(tmp_path / "m.npz", {**arrays, member: values}))


def test_refusals_never_suggest_pickle(saved, tmp_path):
    """issue 13 finding 4: refusing a text file repeated numpy's hint to use allow_pickle."""
    arrays, _ = saved
    (tmp_path / "text.npz").write_text("a text file, not a model\n")
    (tmp_path / "empty.npz").write_bytes(b"")
    np.save(tmp_path / "bare.npy", np.arange(3))
    _write(tmp_path / "objects.npz", {**arrays, "noise": np.array([{}, {}, {}], dtype=object)})
    raw = _write(tmp_path / "good.npz", arrays).read_bytes()
    (tmp_path / "cut.npz").write_bytes(raw[: len(raw) * 2 // 3])
    for name in ("text.npz", "empty.npz", "bare.npy", "objects.npz", "cut.npz"):
        with pytest.raises(ValueError) as info:
            IProMP.load(tmp_path / name)
        assert "pickle" not in _messages(info.value), name


# ----------------------------------------------------------------- finding 5
def test_one_huge_observation_is_rejected_and_never_poisons(model):
    """issue 13 finding 5: one finite observation of about 1e153 made every later window
    raise ``log_likelihood: ... NaN`` and froze the plan."""
    demo = synth.replay(0, 2.0)
    clean, pred = DynamicPredictor(model), DynamicPredictor(model)
    for i, (t, y) in enumerate(zip(demo.times, demo.human)):
        clean.observe(t, y)
        if i == 10:
            pred.observe(t, np.array([1e153, 0.0, 0.0]))
        pred.observe(t, y)
    assert pred.n_rejected == 1 and pred.n_skipped == 1
    assert len(pred.updates) == len(clean.updates) == 10
    np.testing.assert_array_equal(pred.plan()[1], clean.plan()[1])


def test_absolute_timestamps_are_refused(model):
    """issue 13 finding 5: absolute timestamps (1.7e9 s) were accepted and shifted the plan."""
    pred = DynamicPredictor(model)
    with pytest.raises(ValueError, match="absolute"):
        pred.observe(1.7e9, [1.0, 0.0, 0.2])
    with pytest.raises(ValueError, match="absolute"):
        StaticPredictor(model).update(1.7e9)


# ----------------------------------------------------------------- finding 6
@pytest.mark.parametrize("kind", ["duplicated", "constant", "zero"])
def test_fit_refuses_tasks_whose_demos_do_not_differ(demos, kind):
    """issue 13 finding 6: duplicated, constant or all-zero demos were fitted, and the
    predictor later failed with ``cannot reshape array of size 0 into shape (7,0)``."""
    first = [d for d in demos if d.task == "task0"]
    make = {"duplicated": lambda d: first[0],
            "constant": lambda d: synth.Demo(d.times, np.ones_like(d.human),
                                             np.ones_like(d.robot), d.task),
            "zero": lambda d: synth.Demo(d.times, np.zeros_like(d.human),
                                         np.zeros_like(d.robot), d.task)}[kind]
    bad = [make(d) if d.task == "task0" else d for d in demos]
    with pytest.raises(ValueError, match="task 'task0'.*do not differ"):
        IProMP(n_basis=9).fit(bad)
    two = [d for d in demos if d.task == "task0"][:2] + [d for d in demos if d.task == "task1"][:2]
    few = IProMP(n_basis=9).fit(two)            # few demos that differ still fit and predict
    assert np.isfinite(DynamicPredictor(few).command(1.0)[0]).all()


# ----------------------------------------------------------------- finding 9
ENTRIES = {
    "observe(None, y)": lambda m: DynamicPredictor(m).observe(None, [1.0, 0.0, 0.2]),
    "observe(huge int, y)": lambda m: DynamicPredictor(m).observe(10**400, [1.0, 0.0, 0.2]),
    "subsample=inf": lambda m: DynamicPredictor(m, subsample=float("inf")),
    "subsample=True": lambda m: DynamicPredictor(m, subsample=True),
    "n_candidates=None": lambda m: DynamicPredictor(m, n_candidates=None),
    "n_candidates=inf": lambda m: DynamicPredictor(m, n_candidates=float("inf")),
    "refine_steps=None": lambda m: DynamicPredictor(m, refine_steps=None),
    "blend='yes'": lambda m: DynamicPredictor(m, blend="yes"),
    "observe=5": lambda m: DynamicPredictor(m, observe=5),
    "max_time='x'": lambda m: DynamicPredictor(m, max_time="x"),
    "command(None)": lambda m: DynamicPredictor(m).command(None),
    "ratio=None": lambda m: StaticPredictor(m, ratio=None),
    "IProMP(n_basis=None)": lambda m: IProMP(n_basis=None),
    "IProMP(n_basis='9')": lambda m: IProMP(n_basis="9"),
    "IProMP(ridge=10**400)": lambda m: IProMP(ridge=10**400),
    "IProMP(regularizer=True)": lambda m: IProMP(regularizer=True),
    "IProMP(noise_floors=[1])": lambda m: IProMP(noise_floors=[1]),
    "IProMP(priors='ab')": lambda m: IProMP(priors="ab"),
    "IProMP(normalized_basis=1)": lambda m: IProMP(normalized_basis=1),
    "fit(5)": lambda m: IProMP().fit(5),
    "fit(task=None)": lambda m: IProMP(n_basis=7).fit(
        [synth.Demo(np.arange(5.0), np.ones((5, 3)), np.ones((5, 7)), None)] * 2),
    "save(a folder)": lambda m: m.save(tempfile.gettempdir()),
    "load(None)": lambda m: IProMP.load(None),
    "load(5)": lambda m: IProMP.load(5),
}


@pytest.mark.parametrize("name", list(ENTRIES))
def test_public_entries_raise_value_error(model, name):
    """issue 13 finding 9: about 900 inputs raised TypeError or OverflowError (e.g.
    ``observe(None, y)``, ``subsample=inf``, ``IProMP(n_basis=None)``) or were accepted
    (and finding 8: saving to a folder raised IsADirectoryError)."""
    with pytest.raises(ValueError) as info:
        ENTRIES[name](model)
    assert type(info.value) is ValueError


# ---------------------------------------------------------------- finding 10
def test_an_update_before_the_last_one_is_refused(model):
    """issue 13 finding 10: ``update(t)`` earlier than the last update rewrote commands
    already executed."""
    pred = DynamicPredictor(model, dow_t=0.5)
    demo = synth.replay(0, 2.0)
    for t, y in zip(demo.times[:120], demo.human):
        pred.observe(t, y)
    executed = pred.commands(np.linspace(0.0, 1.0, 11))[0]
    with pytest.raises(ValueError, match="last update"):
        pred.update(0.3)
    np.testing.assert_array_equal(pred.commands(np.linspace(0.0, 1.0, 11))[0], executed)
    pred.update(1.5)                              # ahead of the observations (1.19 s)
    with pytest.raises(ValueError, match="previous"):
        pred.observe(1.3, demo.human[130])        # would trigger an update before 1.5 s
