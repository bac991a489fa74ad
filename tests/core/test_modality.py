"""Modalities: validation, layout, selection; a multimodal model's known answers."""

import numpy as np
import pytest

from sandbox.core.interaction import log_marginal_likelihood, observation_matrix
from sandbox.core.likelihood import Scorer
from sandbox.core.modality import (
    Modality,
    check_modalities,
    default_modalities,
    modality_index,
    select,
    slices,
)
from sandbox.core.model import IProMP
from sandbox.core.predictor import DynamicPredictor

from . import synth


def test_modality_validation_and_round_trip():
    m = Modality("emg", ("e0", "e1"), "signal")
    assert m.size == 2 and m.units == "raw"
    assert Modality.from_dict(m.to_dict()) == m
    assert Modality("hand", ("x", "y", "z")).units == "m"
    for bad, message in [(("", ("x",)), "name"), (("a,b", ("x",)), "name"),
                         (("a", ()), "dim names"), (("a", "xyz"), "string"),
                         (("a", ("x", "x")), "repeat"), (("a", ("x",), "force"), "kind")]:
        with pytest.raises(ValueError, match=message):
            Modality(*bad)
    with pytest.raises(ValueError, match="unknown keys"):
        Modality.from_dict({"name": "a", "dims": ["x"], "colour": 1})


def test_layout_helpers():
    mods = synth.layout()
    assert check_modalities(mods, 13) == mods
    assert slices(mods) == {"hand": slice(0, 3), "arm": slice(3, 9), "emg": slice(9, 13)}
    np.testing.assert_array_equal(modality_index(mods), [0] * 3 + [1] * 6 + [2] * 4)
    assert [m.name for m in select(mods, "emg,hand")] == ["emg", "hand"]
    assert select(mods, None) == mods
    assert default_modalities(("a", "b"))[0].name == "hand"
    with pytest.raises(ValueError, match=r"among \['hand', 'arm', 'emg'\].*\['eeg'\]"):
        select(mods, ["hand", "eeg"])
    with pytest.raises(ValueError, match="repeat"):
        select(mods, ["hand", "hand"])
    with pytest.raises(ValueError, match="expected 12 human dims"):
        check_modalities(mods, 12)
    with pytest.raises(ValueError, match="more than one modality"):
        check_modalities([Modality("a", ("x",)), Modality("b", ("x",))])


@pytest.fixture(scope="module")
def multi():
    demos = synth.multimodal(np.random.default_rng(0), n_per_task=8)
    return demos, IProMP(n_basis=11).fit(demos[1:])


def _subset(demos, names):
    """The demos with only the named modalities' columns."""
    mods = [m for m in synth.layout() if m.name in names]
    where = slices(synth.layout())
    cols = np.concatenate([np.arange(where[m.name].start, where[m.name].stop) for m in mods])
    return [synth.MultiDemo(d.times, d.human[:, cols], d.robot, d.task, tuple(mods),
                            tuple(d.human_names[c] for c in cols)) for d in demos]


def test_signal_scale_kappa_and_floors_per_modality(multi):
    demos, model = multi
    assert model.modality_names == ("hand", "arm", "emg")
    np.testing.assert_array_equal(model.scale[:9], 1.0)
    ends = [model.motion_end(d.times, d.robot, d.human) for d in demos[1:]]
    pooled = np.vstack([d.human[: e + 1, 9:] for d, e in zip(demos[1:], ends)])
    assert min(ends) < max(len(d.times) for d in demos) - 1     # the motions were cut
    np.testing.assert_allclose(model.scale[9:], pooled.std(axis=0), rtol=1e-9)
    assert np.all(np.sqrt(model.noise[:9]) >= 0.02 - 1e-12)
    assert np.all(np.sqrt(model.noise[9:]) >= model.signal_floor - 1e-12)
    kappa = np.array([t.weights.reg[:13] / model.noise for t in model.task_models])
    for dims in (slice(0, 3), slice(3, 9), slice(9, 13)):
        np.testing.assert_allclose(kappa[:, dims], kappa[0, dims.start], rtol=1e-12)
    assert len(Scorer(model).groups) == 3


def test_noise_floors_override_per_modality(multi):
    demos, _ = multi
    model = IProMP(n_basis=11, noise_floors={"arm": 0.05, "emg": 0.3}).fit(demos)
    np.testing.assert_allclose(np.sqrt(model.noise[3:9]), 0.05)
    np.testing.assert_allclose(np.sqrt(model.noise[9:]), 0.3)


def test_masking_a_modality_equals_fitting_without_it(multi):
    demos, model = multi
    test = demos[0]
    t, y = test.times[:140:5], test.human[:140:5] / model.scale
    durations = np.array([1.7, 2.0, 2.3])
    spans = np.array([[0, 3], [0, 3]])
    for keep in (["hand"], ["hand", "arm"], ["emg"], ["arm", "emg"]):
        alone = IProMP(n_basis=11).fit(_subset(demos[1:], keep))
        masked = y.copy()
        for m, s in slices(model.modalities).items():
            if m not in keep:
                masked[:, s] = np.nan
        cols = ~np.isnan(masked[0])
        full = Scorer(model).joint(t, masked, durations, spans)
        sub = Scorer(alone).joint(t, masked[:, cols], durations, spans)
        for k in range(2):
            np.testing.assert_allclose(full.loglik[k], sub.loglik[k], rtol=1e-8)


def test_masked_rows_match_the_dense_likelihood(multi):
    """Modalities missing in some rows (dropouts) are masked rows of H (eq. 9)."""
    _, model = multi
    demo = synth.multimodal(np.random.default_rng(3), n_per_task=1)[1]
    t, y = demo.times[:120:6], demo.human[:120:6] / model.scale
    y[3:7, 3:9] = np.nan        # the arm drops out
    y[::4, 9:] = np.nan         # the signal arrives at a lower rate
    y[10, :3] = np.nan
    P, Q = model.n_human, model.n_robot
    scores = Scorer(model).joint(t, y, np.array([1.9, 2.2]), np.array([[0, 2], [0, 2]]))
    for k in range(2):
        w = model.task_models[k].weights
        for j, T in enumerate([1.9, 2.2]):
            H = observation_matrix(model.basis, np.minimum(t / T, 1), P, Q)
            obs = np.hstack([y, np.full((t.size, Q), np.nan)]).ravel()
            noise = np.tile(np.r_[model.noise, np.ones(Q)], t.size)
            ll = log_marginal_likelihood(w.mean, w.cov(), H, obs, noise)
            assert scores.loglik[k][j] == pytest.approx(ll, rel=1e-9)


def test_a_modality_that_alone_separates_tasks_recognises_from_it_alone():
    demos = synth.multimodal(np.random.default_rng(4), n_per_task=10, hand_differs=False)
    model = IProMP(n_basis=11).fit(demos[1:10] + demos[11:])
    for test in (demos[0], demos[10]):
        emg = DynamicPredictor(model, observe=["emg"], dow_t=0.5)
        hand = DynamicPredictor(model, observe="hand", dow_t=0.5)
        for t, y in zip(test.times, test.human):
            emg.observe(t, {"emg": y[9:]})
            hand.observe(t, y[:3])
        assert emg.task_posterior[test.task] > 0.99
        assert 0.05 < hand.task_posterior[test.task] < 0.95     # the hands are alike


def test_observe_errors(multi):
    _, model = multi
    with pytest.raises(ValueError, match=r"this model has \['hand', 'arm', 'emg'\].*\['eeg'\]"):
        DynamicPredictor(model, observe=["eeg"])
    pred = DynamicPredictor(model, observe=["hand", "emg"])
    with pytest.raises(ValueError, match=r"expected 7 values \(hand \(3\), emg \(4\)\), got 9"):
        pred.observe(0.0, np.zeros(9))
    with pytest.raises(ValueError, match=r"among \['hand', 'emg'\], got \['arm'\]"):
        pred.observe(0.0, {"arm": np.zeros(6)})
    with pytest.raises(ValueError, match="shape"):
        pred.observe(0.0, {"emg": np.zeros(3)})


def test_a_dropout_masks_only_its_modality(multi):
    demos, model = multi
    pred = DynamicPredictor(model, subsample=1)
    row = demos[0].human[0].copy()
    row[4] = np.nan                                   # one arm coordinate lost
    pred.observe(0.0, row)
    _, kept = pred.observations()
    assert np.isnan(kept[0, 3:9]).all() and np.isfinite(kept[0, :3]).all()
    np.testing.assert_allclose(kept[0, 9:], row[9:] / model.scale[9:])
    pred.observe(0.01, np.full(13, np.nan))
    assert pred.n_skipped == 1 and len(pred.observations()[0]) == 1


def test_subsampling_counts_each_modality_on_its_own(multi):
    demos, model = multi
    pred = DynamicPredictor(model, subsample=2, dow_t=60.0)
    rows = demos[0].human[:12].copy()
    rows[1::2, 9:] = np.nan            # the signal comes every other row
    for i, row in enumerate(rows):
        pred.observe(0.01 * i, row)
    _, kept = pred.observations()
    hand_kept = np.isfinite(kept[:, 0]).sum()
    emg_kept = np.isfinite(kept[:, 9]).sum()
    assert (hand_kept, emg_kept) == (6, 3)          # 1 in 2 of 12 rows, 1 in 2 of 6 rows
