"""Tests of sandbox.data.signals (EMG envelope: causal, zero-phase, decimation)."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.data.signals import (
    decimate,
    envelope,
    fresh_rows,
    preprocess_signal,
    rectify,
)

CUTOFF = 3.0
TAU = 1.0 / (2.0 * np.pi * CUTOFF)


def bursty_emg(rng: np.random.Generator, n: int = 300, channels: int = 8):
    """Rows like the recorded Myo stream: shared time stamps and re-sent samples."""
    t = np.cumsum(rng.choice([0.0, 0.002, 0.02, 0.035], size=n, p=[0.4, 0.2, 0.2, 0.2]))
    x = rng.uniform(50.0, 900.0, (n, channels)).round()
    resend = np.flatnonzero(rng.random(n) < 0.3)
    for k in resend[resend > 0]:
        x[k] = x[k - 1]
    return t, x


def step_response(stages: int):
    t = np.arange(-0.05, 0.4, 0.001)
    x = (t > -1e-12).astype(float)[:, None]
    # Every row feeds the filter (repeats and zero rows are not fresh rows).
    y = envelope(t, x, cutoff_hz=CUTOFF, stages=stages, min_dt=1e-4, use=np.ones(t.size, bool))
    # The input is held at each new sample over the step before it: the step
    # starts at the last zero sample.
    return t - t[np.argmax(t > -1e-12) - 1], y[:, 0]


# --- causality and zero phase -----------------------------------------------------------


@pytest.mark.parametrize("j", [40, 150, 260])
def test_causal_envelope_uses_no_future_sample(j):
    rng = np.random.default_rng(j)
    t, x = bursty_emg(rng)
    base = envelope(t, x)
    later = x.copy()
    later[j + 1 :] = rng.uniform(0.0, 1000.0, later[j + 1 :].shape)
    changed = envelope(t, later)
    np.testing.assert_array_equal(changed[: j + 1], base[: j + 1])
    assert not np.allclose(changed[j + 1 :], base[j + 1 :])


def test_zero_phase_envelope_looks_ahead():
    rng = np.random.default_rng(0)
    t, x = bursty_emg(rng)
    base = envelope(t, x, causal=False)
    later = x.copy()
    later[151:] += 300.0
    assert not np.allclose(envelope(t, later, causal=False)[:151], base[:151])


def test_gaussian_pulse_keeps_its_peak_time_only_with_zero_phase():
    t = np.arange(0.0, 2.0, 0.01)
    x = (100.0 + 500.0 * np.exp(-0.5 * ((t - 1.0) / 0.08) ** 2))[:, None]
    peak = np.argmax(x[:, 0])
    zero_phase = envelope(t, x, causal=False)[:, 0]
    causal = envelope(t, x, causal=True)[:, 0]
    assert abs(np.argmax(zero_phase) - peak) <= 1
    assert np.argmax(causal) - peak >= 3  # delayed by several samples (~ 2 tau)


# --- known answers ------------------------------------------------------------------------


def test_one_stage_step_response_is_first_order():
    t, y = step_response(1)
    after = t > 0
    np.testing.assert_allclose(y[after], 1 - np.exp(-t[after] / TAU), rtol=1e-3)
    assert np.all(y[t <= 0] == 0.0)


def test_two_stage_step_response_is_second_order():
    t, y = step_response(2)
    after = t > 0
    r = t[after] / TAU
    np.testing.assert_allclose(y[after], 1 - np.exp(-r) * (1 + r), rtol=1e-3)


@pytest.mark.parametrize("causal", [True, False])
@pytest.mark.parametrize("stages", [1, 2, 4])
def test_constant_input_gives_the_constant(causal, stages):
    rng = np.random.default_rng(stages)
    t = np.cumsum(rng.uniform(0.0, 0.04, 200))
    x = np.tile([[250.0, 87.0, 3.5]], (200, 1))
    y = envelope(t, x, causal=causal, stages=stages, use=np.ones(200, bool))
    np.testing.assert_allclose(y, x, rtol=1e-12)


@pytest.mark.parametrize("causal", [True, False])
@pytest.mark.parametrize("stages", [1, 2, 3])
def test_output_is_bounded_by_input_range(causal, stages):
    rng = np.random.default_rng(10 + stages)
    t, x = bursty_emg(rng)
    y = envelope(t, x, causal=causal, stages=stages)
    used = fresh_rows(x)
    first = np.argmax(used)
    assert np.all(np.isnan(y[:first])) and np.all(np.isfinite(y[first:]))
    lo, hi = x[used].min(axis=0), x[used].max(axis=0)
    assert np.all(y[first:] >= lo - 1e-9) and np.all(y[first:] <= hi + 1e-9)


def test_state_starts_at_first_used_sample():
    t = np.array([0.0, 0.1, 0.2, 0.3])
    x = np.array([[np.nan], [400.0], [400.0], [400.0]])
    y = envelope(t, x, use=np.ones(4, bool))
    assert np.isnan(y[0, 0])
    np.testing.assert_array_equal(y[1:, 0], 400.0)


def test_unused_rows_hold_the_state():
    t = np.arange(10) * 0.01
    x = np.arange(10.0)[:, None] * 10
    use = np.zeros(10, bool)
    use[[2, 5, 6]] = True
    y = envelope(t, x, use=use)[:, 0]
    assert np.all(np.isnan(y[:2]))
    np.testing.assert_array_equal(y[2:5], y[2])
    np.testing.assert_array_equal(y[6:], y[6])
    assert y[2] == 20.0 and 20.0 < y[5] < y[6] < 60.0


# --- irregular sampling -------------------------------------------------------------------


def smooth_signal(t):
    return np.c_[300 + 150 * np.sin(2 * np.pi * 0.7 * t), 200 + 80 * np.cos(2 * np.pi * 0.4 * t)]


#: Largest |d smooth_signal / dt| per channel (units/s).
SLOPE = np.array([150 * 2 * np.pi * 0.7, 80 * 2 * np.pi * 0.4])


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("causal", [True, False])
def test_irregular_sampling_matches_the_uniform_grid(causal, seed):
    rng = np.random.default_rng(seed)
    uniform = np.arange(0.0, 4.0, 0.01)
    ref = envelope(uniform, smooth_signal(uniform), causal=causal, min_dt=0.005)
    # Random steps of 5-30 ms; 35 % of the rows are taken min_dt = 5 ms after the
    # previous one but stamped with its time (bursts).
    burst = rng.random(400) < 0.35
    burst[0] = False
    taken = np.cumsum(np.where(burst, 0.005, rng.uniform(0.005, 0.03, 400)))
    stamped = taken.copy()
    for k in np.flatnonzero(burst):
        stamped[k] = stamped[k - 1]
    taken, stamped = taken[taken < 4.0], stamped[taken < 4.0]
    assert np.mean(np.diff(stamped) == 0) > 0.25
    y = envelope(stamped, smooth_signal(taken), causal=causal, min_dt=0.005)
    at = (stamped > 0.5) & (stamped < 3.5)
    expected = np.column_stack([np.interp(stamped[at], uniform, c) for c in ref.T])
    # The input is held over each step: each grid is off the continuous envelope
    # by at most slope * step; a burst row's stamp is 5 ms early. The zero-phase
    # pass cancels most of the hold's lead.
    bound = SLOPE * (np.diff(taken).max() + 0.01 + 0.005)
    assert np.all(np.abs(y[at] - expected) <= bound)
    if not causal:
        assert np.all(np.abs(y[at] - expected) <= 0.5 * bound)


# --- fresh rows and decimation ------------------------------------------------------------


def test_fresh_rows_skip_repeats_nan_and_zero_rows():
    x = np.array([
        [0.0, 0.0],       # all zero
        [1.0, 2.0],       # fresh
        [1.0, 2.0],       # repeat
        [np.nan, 2.0],    # missing
        [1.0, 2.0],       # repeat of the previous fresh row (across the NaN row)
        [1.0, 3.0],       # fresh
        [0.0, 0.0],       # all zero
        [1.0, 2.0],       # a re-sent older sample (A, B, A)
        [0.0, 5.0],       # fresh: one zero channel is a value
        [1.0, 2.0],       # fresh again once it left the window of the last 2
    ])
    np.testing.assert_array_equal(
        fresh_rows(x, repeat_window=2),
        [False, True, False, False, False, True, False, False, True, True]
    )
    with pytest.raises(ValueError, match="repeat_window"):
        fresh_rows(x, repeat_window=0)


def test_inputs_are_not_modified():
    x = np.array([[1.0, np.nan], [2.0, 2.0]])
    before = x.copy()
    fresh_rows(x)
    rectify(x)
    envelope([0.0, 0.1], x)
    preprocess_signal([0.0, 0.1], x, "causal")
    np.testing.assert_array_equal(x, before)


def test_rectify_is_absolute_value_with_nan():
    x = np.array([[-3.0, 2.0], [np.nan, -0.5]])
    np.testing.assert_array_equal(rectify(x), [[3.0, 2.0], [np.nan, 0.5]])


@pytest.mark.parametrize("rate", [10.0, 30.0, 60.0])
def test_decimate_spacing_subset_and_causality(rate):
    rng = np.random.default_rng(int(rate))
    t, x = bursty_emg(rng, n=400)
    keep = fresh_rows(x)
    kept = decimate(t, keep, rate)
    assert np.all(keep[kept])
    assert np.all(np.diff(t[kept]) >= 1.0 / rate - 1e-9)
    # Greedy: a candidate is dropped only if it is too close to the last kept row.
    last = np.maximum.accumulate(np.where(kept, np.arange(t.size), 0))
    dropped = keep & ~kept
    assert np.all(t[dropped] - t[last[dropped]] < 1.0 / rate - 1e-9)
    j = 200
    other = keep.copy()
    other[j + 1 :] = rng.random(t.size - j - 1) < 0.5
    np.testing.assert_array_equal(decimate(t, other, rate)[: j + 1], kept[: j + 1])


def test_decimate_keeps_a_row_exactly_one_period_later():
    t = np.array([0.0, 0.1, 0.2, 0.25, 0.3])
    kept = decimate(t, np.ones(5, bool), 10.0)
    np.testing.assert_array_equal(kept, [True, True, True, False, True])


# --- preprocess_signal ---------------------------------------------------------------------


def test_preprocess_modes_on_synthetic_stream():
    rng = np.random.default_rng(7)
    t, x = bursty_emg(rng)
    fresh = fresh_rows(x)
    out, measured, counts = preprocess_signal(t, x, "none")
    np.testing.assert_array_equal(out, x)
    np.testing.assert_array_equal(measured, fresh)
    out, measured, counts = preprocess_signal(t, x, "causal")
    np.testing.assert_array_equal(measured, decimate(t, fresh, 30.0))
    np.testing.assert_array_equal(out[measured], envelope(t, x)[measured])
    assert np.all(np.isnan(out[~measured]))
    out, measured, counts = preprocess_signal(t, x, "smooth")
    np.testing.assert_array_equal(out, envelope(t, x, causal=False))
    assert counts == {
        "signal_fresh_rows": int(fresh.sum()), "signal_output_rows": t.size - np.argmax(fresh),
        "signal_zero_rows": 0, "signal_missing_rows": 0, "signal_constant": False,
    }


def test_preprocess_counts_zero_missing_and_constant():
    t = np.arange(6) * 0.01
    x = np.array([[0, 0], [1, 5], [np.nan, 5], [2, 5], [2, 5], [0, 0]], dtype=float)
    _, _, counts = preprocess_signal(t, x, "none")
    assert counts["signal_zero_rows"] == 2 and counts["signal_missing_rows"] == 1
    assert counts["signal_fresh_rows"] == 2 and counts["signal_constant"] is True
    _, _, counts = preprocess_signal(t[:2], x[:2], "smooth")
    assert counts["signal_constant"] is True  # fewer than 2 fresh rows


def read_emg(path):
    header = path.open().readline().strip().split(",")
    cols = [header.index("t")] + [header.index(f"emg{i}") for i in range(8)]
    table = np.loadtxt(path, delimiter=",", skiprows=1, usecols=cols, ndmin=2)
    return table[:, 0], table[:, 1:]


def test_preprocess_recorded_trials(recorded_dir):
    trials = [sorted((recorded_dir / task).glob("*.csv"))[0] for task in
              ("gummed_paper", "measurement_tape", "pencil_box", "screw_driver")]
    for path in trials:
        t, x = read_emg(path)
        duration = t[-1] - t[0]
        out, measured, counts = preprocess_signal(t, x, "causal")
        assert np.all(np.isfinite(out[measured])) and np.all(np.isnan(out[~measured]))
        assert measured.sum() <= 30.0 * duration + 1
        assert measured.sum() >= 0.5 * 30.0 * duration
        assert counts["signal_output_rows"] == measured.sum()
        assert not counts["signal_constant"]
        out, measured, counts = preprocess_signal(t, x, "smooth")
        first = np.argmax(measured)
        assert np.all(np.isfinite(out[first:])) and np.all(np.isnan(out[:first]))
        assert counts["signal_fresh_rows"] == measured.sum() > 40 * duration


# --- validation ---------------------------------------------------------------------------

T3 = [0.0, 0.1, 0.2]
X3 = [[1.0], [2.0], [3.0]]


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: envelope([0.0, 0.2, 0.1], X3), r"t\[1\]=0.2 followed by t\[2\]=0.1"),
        (lambda: envelope([[0.0, 0.1, 0.2]], X3), "times: expected a 1-D"),
        (lambda: envelope([0.0, np.nan, 0.2], X3), "times: expected finite"),
        (lambda: envelope([0.0, np.inf, 0.2], X3), "times: expected finite"),
        (lambda: envelope(T3, [1.0, 2.0, 3.0]), "values: expected a 2-D"),
        (lambda: envelope(T3, X3[:2]), r"values: expected shape \(3, 'n'\)"),
        (lambda: envelope(T3, [[1.0], [np.inf], [3.0]]), "values: expected finite"),
        (lambda: envelope(T3, np.zeros((3, 0))), "values: expected at least 1 channel"),
        (lambda: envelope(T3, X3, cutoff_hz=0.0), "cutoff_hz: expected a finite number > 0"),
        (lambda: envelope(T3, X3, min_dt=-1.0), "min_dt: expected a finite number > 0"),
        (lambda: envelope(T3, X3, stages=0), "stages: expected an integer >= 1"),
        (lambda: envelope(T3, X3, stages=1.5), "stages: expected an integer >= 1"),
        (lambda: envelope(T3, X3, stages=True), "stages: expected an integer >= 1"),
        (lambda: envelope(T3, X3, use=[1, 0, 1]), "use: expected a boolean array"),
        (lambda: envelope(T3, X3, use=[True, False]), r"use: expected .* shape \(3,\)"),
        (lambda: rectify([1.0, 2.0]), "values: expected a 2-D"),
        (lambda: rectify([[np.inf]]), "values: expected finite"),
        (lambda: fresh_rows([1.0, 2.0]), "values: expected a 2-D"),
        (lambda: decimate(T3, [True, True], 30.0), "keep: expected a boolean array"),
        (lambda: decimate(T3, [True] * 3, 0.0), "rate_hz: expected a finite number > 0"),
        (lambda: decimate([0.2, 0.1, 0.3], [True] * 3, 30.0), "times: expected non-decreasing"),
        (lambda: preprocess_signal(T3, X3, "fast"), r"mode: .*\['none', 'causal', 'smooth'\]"),
        (lambda: preprocess_signal(T3, X3, "none", rate_hz=-1.0), "rate_hz: expected"),
        (lambda: preprocess_signal(T3, X3, "none", cutoff_hz=np.nan), "cutoff_hz: expected"),
        (lambda: preprocess_signal(T3, X3, "none", min_dt=0.0), "min_dt: expected"),
        (lambda: preprocess_signal(T3, X3, "none", stages=0), "stages: expected"),
        (lambda: preprocess_signal([0.0, 0.1], X3, "smooth"), "values: expected shape"),
        (lambda: preprocess_signal([0.1, 0.0, 0.2], X3, "causal"), "times: expected non-decr"),
    ],
)
def test_value_errors(call, match):
    with pytest.raises(ValueError, match=match):
        call()
