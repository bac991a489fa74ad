"""Familiarity (sandbox.core.familiarity): known answers on synthetic motions, properties,
calibration honesty, and the model file round trip."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from sandbox.core import DynamicPredictor, IProMP
from sandbox.core.evidence import COMPONENTS, TIMING
from sandbox.core.familiarity import LEVELS, SCORE_NAMES, Calibration, statistic, stream_record

from . import synth

NOISE = 0.01          # m, the live streams' tracker noise (the training demos have 0.002)
OPTIONS = {"subsample": 5, "n_candidates": 20}


def noisy(demo, rng):
    return synth.Demo(demo.times, demo.human + NOISE * rng.standard_normal(demo.human.shape),
                      demo.robot, demo.task)


@pytest.fixture(scope="module")
def model():
    """Tasks 0 and 1 of synth, calibrated on noisy streams of the training demos."""
    train = synth.demos(np.random.default_rng(0), n_per_task=8, n_tasks=2)
    model = IProMP(n_basis=9).fit(train)
    rng = np.random.default_rng(1)
    model.calibrate(train, [noisy(d, rng) for d in train], **OPTIONS)
    return model


def stream(model, demo, **options):
    pred = DynamicPredictor(model, dow_t=0.2, **{**OPTIONS, **options})
    for t, y in zip(demo.times, demo.human):
        pred.observe(t, y)
    return pred


def unseen(task: int, seed: int):
    """A new motion of synth task ``task`` (2 is never trained), as a live stream."""
    rng = np.random.default_rng(seed)
    demo = synth.demos(rng, n_per_task=1, n_tasks=3)[task]
    return noisy(demo, rng)


def still_hand(duration: float = 2.0, seed: int = 3):
    """The hand held still where the motions start, with tracker noise."""
    rng = np.random.default_rng(seed)
    demo = synth.replay(0, duration)
    human = np.repeat(demo.human[:1], demo.times.size, axis=0)
    return synth.Demo(demo.times, human + NOISE * rng.standard_normal(human.shape),
                      demo.robot, "still")


# ------------------------------------------------------------------ known answers
@pytest.mark.parametrize("task", [0, 1])
def test_a_new_motion_of_a_trained_task_is_familiar(model, task):
    pred = stream(model, unseen(task, seed=10 + task))
    fam = [u.familiarity for u in pred.updates]
    assert pred.familiar is True
    assert min(fam) >= model.calibration.threshold
    assert pred.task == f"task{task}"


def test_a_motion_of_another_shape_is_unfamiliar(model):
    pred = stream(model, unseen(2, seed=12))
    assert pred.familiar is False
    assert pred.familiarity < 0.1 * model.calibration.threshold
    assert max(pred.task_posterior.values()) > 0.99    # the posterior alone is confident


def test_a_still_hand_becomes_unfamiliar(model):
    pred = stream(model, still_hand())
    assert pred.updates[0].familiarity >= model.calibration.threshold   # could be a start
    assert pred.familiar is False


def test_none_before_the_first_update_and_without_calibration(model):
    pred = DynamicPredictor(model, dow_t=0.2, **OPTIONS)
    assert pred.familiarity is None and pred.familiar is None
    bare = IProMP(n_basis=9).fit(synth.demos(np.random.default_rng(0), n_per_task=4))
    assert bare.calibration is None
    pred = stream(bare, unseen(0, seed=10))
    assert pred.updates and pred.familiarity is None and pred.familiar is None
    assert all(u.familiarity is None for u in pred.updates)


def test_marginal_likelihood_has_no_familiarity(model):
    pred = stream(model, unseen(0, seed=10), likelihood="marginal")
    assert pred.updates and pred.familiarity is None


def test_predictions_do_not_change(model):
    """The familiarity only reads the prediction: plan and posteriors are the same."""
    demo = unseen(1, seed=11)
    with_cal = stream(model, demo)
    saved, model.calibration = model.calibration, None
    try:
        without = stream(model, demo)
    finally:
        model.calibration = saved
    for a, b in zip(with_cal.updates, without.updates):
        np.testing.assert_array_equal(a.task_posterior, b.task_posterior)
    np.testing.assert_array_equal(with_cal.plan()[1], without.plan()[1])


def test_refit_drops_the_calibration(model):
    other = IProMP(n_basis=9).fit(synth.demos(np.random.default_rng(4), n_per_task=3))
    other.calibration = model.calibration
    other.fit(synth.demos(np.random.default_rng(5), n_per_task=3))
    assert other.calibration is None


# ------------------------------------------------------------------ properties
def test_familiarity_is_in_0_1_and_falls_with_the_statistic(model):
    cal = model.calibration
    values = np.geomspace(1e-4, 1e4, 200)
    for t in (0.0, 1.0, 5.0):
        fam = np.array([cal.familiarity(t, [v, 0.0, 0.0, 0.0, 0.0], 0) for v in values])
        assert np.all((fam > 0) & (fam <= 1))
        assert np.all(np.diff(fam) <= 0)
        assert fam[0] == 1.0 and fam[-1] < 1e-3
    assert np.isnan(cal.familiarity(1.0, [float("nan"), 0.0, 0.0, 0.0, 0.0], 1))


def test_familiarity_of_a_bin_matches_its_quantiles():
    """Known answer: one bin with values 1..100: the value at level 0.5 has familiarity 0.5."""
    values = np.arange(1.0, 101.0)
    cal = Calibration.from_records([(np.zeros(100), values, np.zeros(100, int))], 1, edges=[0.0])
    median = float(np.quantile(values, 0.5))
    assert cal.familiarity(3.0, median, 0) == pytest.approx(0.5)
    assert cal.familiarity(0.0, 0.5, 0) == 1.0


def test_each_task_is_ranked_against_its_own_updates():
    """Task 1's updates score 10x task 0's: a value typical of task 1 is unfamiliar for 0."""
    rng = np.random.default_rng(8)
    records = [(np.arange(5) * 0.2, rng.lognormal(0.0, 0.2, 5) * 10.0 ** (i % 2),
                np.full(5, i % 2)) for i in range(40)]
    cal = Calibration.from_records(records, 2, edges=[0.0])
    assert cal.familiarity(0.5, 10.0, 1) == pytest.approx(0.5, abs=0.1)
    assert cal.familiarity(0.5, 10.0, 0) < 1e-3


def test_threshold_grows_with_alpha():
    rng = np.random.default_rng(6)
    records = [(np.arange(8) * 0.2, rng.lognormal(0, 0.5, 8), np.zeros(8, int))
               for _ in range(60)]
    thresholds = [Calibration.from_records(records, 1, alpha=a, edges=[0.0, 0.5, 1.0]).threshold
                  for a in (0.01, 0.05, 0.2, 0.5)]
    assert np.all(np.diff(thresholds) > 0)


def test_a_new_motion_like_the_calibration_ones_fires_at_about_alpha():
    """Exchangeable synthetic records: the share of fresh ones flagged at some update is
    about alpha (binomial 99.9 % bounds)."""
    rng = np.random.default_rng(7)

    def record():
        t = np.arange(10) * 0.2
        k = rng.integers(0, 2, 10)
        return t, rng.lognormal(0.3 * t + k, 0.4 + 0.1 * rng.random()), k

    alpha, n = 0.1, 400
    cal = Calibration.from_records([record() for _ in range(100)], 2, alpha=alpha,
                                   edges=[0.0, 0.6, 1.2])
    flagged = [min(cal.familiarity(*update) for update in zip(*record())) < cal.threshold
               for _ in range(n)]
    assert 0.05 < np.mean(flagged) < 0.17


def test_statistic_is_the_mahalanobis_term_of_the_likelihood(model):
    """m n = d^T C^-1 d of the chosen task at its MAP duration, against a dense solve."""
    from sandbox.core.inference import predict
    from sandbox.core.likelihood import Scorer

    demo = unseen(0, seed=10)
    t, y = demo.times[::5], demo.human[::5]
    pred = predict(model, Scorer(model), t, y, n_candidates=20)
    k = int(np.argmax(pred.task_posterior))
    task = model.task_models[k]
    z = np.minimum(t / pred.durations[k], 1.0)
    Psi = model.basis.evaluate(z)
    P = model.n_human
    H = np.kron(np.eye(P), Psi)                                  # (s P, P N), dim-major
    human = task.weights.dims(slice(0, P))
    cov = (H @ human.cov() @ H.T + np.kron(np.diag(model.noise), np.eye(t.size)))
    d = y.T.ravel() - H @ human.mean
    expected = d @ np.linalg.solve(cov, d) / y.size
    assert pred.n_values == y.size
    assert statistic(pred) == pytest.approx(expected, rel=1e-6)


# ------------------------------------------------------------------ errors
def test_bad_records_are_value_errors():
    with pytest.raises(ValueError, match="at least one calibration motion"):
        Calibration.from_records([], 1)
    with pytest.raises(ValueError, match="one length"):
        Calibration.from_records([(np.zeros(3), np.ones(2), np.zeros(3, int))], 1)
    with pytest.raises(ValueError, match="task indices"):
        Calibration.from_records([(np.zeros(3), np.ones(3), np.full(3, 2))], 2)
    with pytest.raises(ValueError, match="alpha"):
        Calibration.from_records([(np.zeros(3), np.ones(3), np.zeros(3, int))], 1, alpha=2.0)


def test_inconsistent_calibration_is_refused():
    q = np.tile(LEVELS, (1, 2, 1))
    with pytest.raises(ValueError, match="edges"):
        Calibration(np.array([0.5, 1.0]), q, np.ones((1, 2)), 0.1, 0.05)
    with pytest.raises(ValueError, match="non-decreasing"):
        Calibration(np.array([0.0, 1.0]), q[:, :, ::-1], np.ones((1, 2)), 0.1, 0.05)
    with pytest.raises(ValueError, match="counts"):
        Calibration(np.array([0.0, 1.0]), q, np.ones(2), 0.1, 0.05)
    with pytest.raises(ValueError, match="threshold"):
        Calibration(np.array([0.0, 1.0]), q, np.ones((1, 2)), 1.5, 0.05)


def test_stream_record_matches_the_predictor(model):
    demo = unseen(0, seed=10)
    times, stats, tasks = stream_record(model, demo.times, demo.human, **OPTIONS)
    pred = stream(model, demo)
    np.testing.assert_allclose(times, [u.time for u in pred.updates])
    assert [model.tasks[k] for k in tasks] == [u.task for u in pred.updates]
    fam = [model.calibration.familiarity(*update) for update in zip(times, stats, tasks)]
    np.testing.assert_allclose(fam, [u.familiarity for u in pred.updates], rtol=1e-9)


# ------------------------------------------------------------------ model files
def test_round_trip_keeps_the_calibration(model, tmp_path):
    model.save(tmp_path / "m.npz")
    loaded = IProMP.load(tmp_path / "m.npz")
    a, b = model.calibration, loaded.calibration
    np.testing.assert_array_equal(a.edges, b.edges)
    np.testing.assert_array_equal(a.quantiles, b.quantiles)
    np.testing.assert_array_equal(a.counts, b.counts)
    np.testing.assert_array_equal(a.extra, b.extra)
    assert (a.threshold, a.alpha, a.subsample, a.dow_t, a.n_motions, a.components) == (
        b.threshold, b.alpha, b.subsample, b.dow_t, b.n_motions, b.components)
    demo = unseen(2, seed=12)
    assert [u.familiarity for u in stream(model, demo).updates] == [
        u.familiarity for u in stream(loaded, demo).updates]


def test_files_without_a_calibration_load_with_none(model, tmp_path):
    path = tmp_path / "m.npz"
    model.save(path)
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files if not k.startswith("familiarity")}
    meta = json.loads(str(arrays["metadata"]))
    del meta["familiarity"]
    np.savez(tmp_path / "old.npz", **{**arrays, "metadata": np.array(json.dumps(meta))})
    old = IProMP.load(tmp_path / "old.npz")
    assert old.calibration is None
    assert stream(old, unseen(0, seed=10)).familiarity is None


def test_files_before_the_timing_evidence_rank_the_mahalanobis_term(model, tmp_path):
    """A file with a calibration but no ``components`` (before issue 30) loads as a
    calibration of the Mahalanobis term alone, and the predictors rank that term."""
    path = tmp_path / "m.npz"
    model.save(path)
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files if k != "familiarity_extra"}
    meta = json.loads(str(arrays["metadata"]))
    del meta["familiarity"]["components"]
    np.savez(tmp_path / "old.npz", **{**arrays, "metadata": np.array(json.dumps(meta))})
    old = IProMP.load(tmp_path / "old.npz")
    assert old.calibration.components == ("mahalanobis",) and old.calibration.extra is None
    demo = unseen(0, seed=10)
    times, stats, tasks = stream_record(old, demo.times, demo.human, score="mahalanobis",
                                        **OPTIONS)
    fam = [old.calibration.familiarity(*update) for update in zip(times, stats, tasks)]
    np.testing.assert_allclose(fam, [u.familiarity for u in stream(old, demo).updates])


def test_the_file_keeps_the_filing_and_older_files_load_it_as_unknown(model, tmp_path):
    """``cells`` round-trips; a file without it (before own-task cells) loads with None and
    ranks the same; a filing the code does not know is a one-line ValueError."""
    path = tmp_path / "m.npz"
    model.save(path)
    assert IProMP.load(path).calibration.cells == model.calibration.cells
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    meta = json.loads(str(arrays["metadata"]))
    for cells, expected in ((None, None), ("chosen", "chosen"), ("mine", ValueError)):
        if cells is None:
            meta["familiarity"].pop("cells", None)
        else:
            meta["familiarity"]["cells"] = cells
        np.savez(tmp_path / "v.npz", **{**arrays, "metadata": np.array(json.dumps(meta))})
        if expected is ValueError:
            with pytest.raises(ValueError, match=r"familiarity cells: expected one of "
                                                 r"\['own', 'chosen'\], got mine"):
                IProMP.load(tmp_path / "v.npz")
        else:
            loaded = IProMP.load(tmp_path / "v.npz").calibration
            assert loaded.cells == expected
            np.testing.assert_array_equal(loaded.stack, model.calibration.stack)


def test_files_before_the_goal_rank_their_four_statistics(model, tmp_path):
    """A file calibrated on the four timing statistics (before the goal) loads, and the
    predictors rank those four of the five, as the calibration's own ranking does."""
    path = tmp_path / "m.npz"
    model.save(path)
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    meta = json.loads(str(arrays["metadata"]))
    meta["familiarity"]["components"] = list(TIMING)
    arrays["familiarity_extra"] = arrays["familiarity_extra"][:3]
    np.savez(tmp_path / "old.npz", **{**arrays, "metadata": np.array(json.dumps(meta))})
    old = IProMP.load(tmp_path / "old.npz")
    assert old.calibration.components == TIMING and old.calibration.extra.shape[0] == 3
    demo = unseen(0, seed=10)
    times, stats, tasks = stream_record(old, demo.times, demo.human, **OPTIONS)
    fam = [old.calibration.familiarity(t, v[:4], k) for t, v, k in zip(times, stats, tasks)]
    np.testing.assert_allclose(fam, [u.familiarity for u in stream(old, demo).updates])


@pytest.mark.parametrize("score", ["goal", "all"])
def test_a_goal_or_position_calibration_ranks_its_statistics_and_round_trips(score, tmp_path):
    """Five statistics with the goal, six with the goal and the position: the predictors
    compute only those and rank them as the calibration does, before and after a file."""
    train = synth.demos(np.random.default_rng(0), n_per_task=4, n_tasks=2)
    bare = IProMP(n_basis=9).fit(train)
    cal = bare.calibrate(train, score=score, **OPTIONS)
    names = SCORE_NAMES[score]
    assert cal.components == names and cal.extra.shape[0] == len(names) - 1
    bare.save(tmp_path / "m.npz")
    loaded = IProMP.load(tmp_path / "m.npz")
    assert loaded.calibration.components == names
    assert cal.motion is None and loaded.calibration.motion is None
    # the file keeps the own-task cells' quantiles, threshold and which filing made them
    assert cal.cells == "own" and loaded.calibration.cells == "own"
    np.testing.assert_array_equal(loaded.calibration.stack, cal.stack)
    assert loaded.calibration.threshold == cal.threshold
    motion = np.array([[0.5, 1.0, 2.0], [0.1, 3.0, 4.0]])    # per_motion=True keeps these
    bare.calibration = replace(cal, motion=motion)
    bare.save(tmp_path / "p.npz")
    np.testing.assert_array_equal(IProMP.load(tmp_path / "p.npz").calibration.motion, motion)
    demo = unseen(1, seed=11)
    times, stats, tasks = stream_record(loaded, demo.times, demo.human, **OPTIONS)
    assert stats.shape == (times.size, len(COMPONENTS))
    fam = [loaded.calibration.familiarity(*update) for update in zip(times, stats, tasks)]
    np.testing.assert_allclose(fam, [u.familiarity for u in stream(loaded, demo).updates])


def test_a_mahalanobis_calibration_round_trips(tmp_path):
    train = synth.demos(np.random.default_rng(0), n_per_task=4, n_tasks=2)
    bare = IProMP(n_basis=9).fit(train)
    cal = bare.calibrate(train, score="mahalanobis", **OPTIONS)
    assert cal.components == ("mahalanobis",) and cal.extra is None
    bare.save(tmp_path / "m.npz")
    with np.load(tmp_path / "m.npz") as data:
        assert "familiarity_extra" not in data.files
        assert "components" not in json.loads(str(data["metadata"]))["familiarity"]
    assert IProMP.load(tmp_path / "m.npz").calibration.components == ("mahalanobis",)


def test_tampered_calibration_is_refused(model, tmp_path):
    path = tmp_path / "m.npz"
    model.save(path)
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    bad = arrays["familiarity_quantiles"].copy()
    bad[0, 0] = bad[0, 0][::-1] + 1.0
    np.savez(tmp_path / "bad.npz", **{**arrays, "familiarity_quantiles": bad})
    with pytest.raises(ValueError, match="bad.npz.*non-decreasing"):
        IProMP.load(tmp_path / "bad.npz")
    meta = json.loads(str(arrays["metadata"]))
    meta["familiarity"]["threshold"] = "high"
    np.savez(tmp_path / "meta.npz", **{**arrays, "metadata": np.array(json.dumps(meta))})
    with pytest.raises(ValueError, match="threshold"):
        IProMP.load(tmp_path / "meta.npz")
    meta["familiarity"]["threshold"] = 0.1
    meta["familiarity"]["components"] = ["mahalanobis", "made_up", "x", "y"]
    np.savez(tmp_path / "names.npz", **{**arrays, "metadata": np.array(json.dumps(meta))})
    with pytest.raises(ValueError, match="components"):
        IProMP.load(tmp_path / "names.npz")
    del arrays["familiarity_extra"]
    np.savez(tmp_path / "extra.npz", **arrays)
    with pytest.raises(ValueError, match="familiarity_extra"):
        IProMP.load(tmp_path / "extra.npz")
    del arrays["familiarity_counts"]
    np.savez(tmp_path / "short.npz", **arrays)
    with pytest.raises(ValueError, match="familiarity_counts"):
        IProMP.load(tmp_path / "short.npz")


@pytest.mark.parametrize("cells", ["own", "chosen"])
def test_a_calibration_on_fresh_motions_streams_them_by_the_model_itself(model, cells):
    """``refit=False`` (the default models' split-conformal calibration): each fresh
    motion is streamed by the fitted model, no leave-one-out refit; its cells are filed
    under each motion's own task (default) or the chosen one."""
    import copy

    from sandbox.core.familiarity import EDGES

    rng = np.random.default_rng(11)
    fresh = [noisy(d, rng) for d in synth.demos(rng, n_per_task=6, n_tasks=2)]
    other = copy.copy(model)
    cal = other.calibrate(fresh, refit=False, cells=cells, **OPTIONS)
    assert other.calibration is cal and model.calibration is not cal and cal.cells == cells
    records = [stream_record(model, d.times - d.times[0], d.human, dow_t=0.2,
                             own=model.task_index(d.task), **OPTIONS) for d in fresh]
    own = [(t, u[:, :len(TIMING)], np.full(t.size, model.task_index(d.task)))
           for (t, _, _, u), d in zip(records, fresh)]
    records = [(t, v[:, :len(TIMING)], k) for t, v, k, _ in records]      # the default score
    mean = float(np.dot(model.priors, [t.mean_duration for t in model.task_models]))
    want = Calibration.from_records(records, 2, alpha=0.05, edges=np.array(EDGES) * mean,
                                    own=own if cells == "own" else None,
                                    subsample=OPTIONS["subsample"], dow_t=0.2)
    np.testing.assert_array_equal(cal.quantiles, want.quantiles)
    assert cal.threshold == want.threshold


def test_a_calibration_gated_to_the_ongoing_motion_judges_no_update_past_its_end(model,
                                                                                tmp_path):
    """``end_prob``: the predictor's familiarity is None from the first update whose
    probability that the motion ended reached it (latched), as the calibration's records
    were cut; before, the calibration ranks as always. The file keeps the gate."""
    import copy

    rng = np.random.default_rng(13)
    fresh = [noisy(d, rng) for d in synth.demos(rng, n_per_task=6, n_tasks=2)]
    gated = copy.copy(model)
    cal = gated.calibrate(fresh, refit=False, end_prob=0.5, **OPTIONS)
    assert cal.end_prob == 0.5
    demo = unseen(0, seed=14)                          # held 1 s at its end: it has ended
    dt = demo.times[1] - demo.times[0]
    times = np.r_[demo.times, demo.times[-1] + dt * np.arange(1, int(1.0 / dt))]
    human = np.vstack([demo.human, np.repeat(demo.human[-1:], times.size - demo.times.size, 0)])
    held = synth.Demo(times, human + NOISE * rng.standard_normal(human.shape), demo.robot, "0")
    at, stats, tasks, ended = stream_record(gated, held.times, held.human, ended=True, **OPTIONS)
    past = np.maximum.accumulate(ended) >= 0.5
    assert past.any() and not past[0]
    fam = [u.familiarity for u in stream(gated, held).updates]
    assert all(f is None for f, p in zip(fam, past) if p)
    np.testing.assert_allclose([f for f, p in zip(fam, past) if not p],
                               [cal.familiarity(*u) for u in zip(at[~past], stats[~past],
                                                                 tasks[~past])], rtol=1e-9)
    gated.save(tmp_path / "gated.npz")
    assert IProMP.load(tmp_path / "gated.npz").calibration.end_prob == 0.5
    assert model.calibration.end_prob is None


def test_the_statistics_under_a_task_are_the_chosen_ones_where_it_was_chosen(model):
    """``stream_record(..., own=k)``: at updates that chose k the statistics under k are the
    recorded ones; under a task never chosen they differ (its own factor and priors), and
    the records' other entries do not change. A task index out of range is refused."""
    demo = unseen(1, seed=3)
    t = demo.times - demo.times[0]
    at, stats, tasks = stream_record(model, t, demo.human, dow_t=0.2, **OPTIONS)
    under = {}
    for k in (0, 1):
        at_k, stats_k, tasks_k, under[k] = stream_record(model, t, demo.human, dow_t=0.2,
                                                         own=k, **OPTIONS)
        np.testing.assert_array_equal(at_k, at)
        np.testing.assert_array_equal(stats_k, stats)
        np.testing.assert_array_equal(tasks_k, tasks)
        np.testing.assert_array_equal(under[k][tasks == k], stats[tasks == k])
    assert np.all(tasks == 1)                       # a motion of task 1 ...
    assert np.all(under[0][:, 0] > stats[:, 0])      # ... fits task 0 worse at every update
    with pytest.raises(ValueError, match="own"):
        stream_record(model, t, demo.human, own=2, **OPTIONS)


def test_interleaved_demos_keep_the_full_models_task_indices_in_every_record():
    """Leaving out a task's first demo must not reorder the tasks: a record's task indices
    (and its own-task statistics) are the full model's, whatever the demos' order."""
    from sandbox.core.familiarity import loo_records

    train = synth.demos(np.random.default_rng(0), n_per_task=3, n_tasks=2)
    interleaved = [d for pair in zip(*[[d for d in train if d.task == k]
                                       for k in ("task0", "task1")]) for d in pair]
    assert [d.task for d in interleaved[:2]] == ["task0", "task1"]
    model = IProMP(n_basis=9).fit(interleaved)
    records = loo_records(model, interleaved, labelled=True, **OPTIONS)
    for demo, (_, _, chosen, own) in zip(interleaved, records):
        assert chosen[-1] == model.task_index(demo.task)    # the motion recognised at its end
        assert own.shape[0] == chosen.size
