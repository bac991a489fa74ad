"""Muscle-activity envelope of a recorded "signal" column group (Myo EMG).

A signal is a group of C channels sampled alongside the motion, here the 8 Myo
EMG channels ``emg0``..``emg7`` of the recorded handovers: non-negative raw
units in the hundreds, rows at ~100 rows/s in bursts (many rows share their
time stamp) and many rows re-sending the previous sample. Numpy only.

Three preprocessing modes (:func:`preprocess_signal`), here with the default
``envelope`` filter (``lowpass`` skips the rectification, for signed signals
such as a force or a torque; ``none`` keeps the values):

- ``"none"``: the values unchanged; the rows carrying a new sample are marked.
- ``"causal"`` (live test streams): rectified, causal envelope, output only at
  new-sample rows at most ``rate_hz`` apart (:func:`decimate`), NaN elsewhere.
- ``"smooth"`` (training demonstrations): rectified, zero-phase envelope, output
  at every row from the first new sample on.

Filter (:func:`envelope`): ``n = stages`` identical first-order low-pass stages
in cascade, time constant :math:`\\tau = 1 / (2 \\pi f_c)`,

.. math::

    \\tau \\dot s_1 = x - s_1,\\qquad \\tau \\dot s_j = s_{j-1} - s_j\\quad (j = 2..n).

Over the step from one used sample to the next the input is held at the new
sample ``x``; with :math:`r = \\Delta t_{\\mathrm{eff}} / \\tau`,
:math:`\\Delta t_{\\mathrm{eff}} = \\Delta t` (or :math:`\\Delta t_{\\min}` for a sample
sharing the previous one's time stamp), the exact
solution is

.. math::

    s_j \\leftarrow x + e^{-r} \\sum_{i=1}^{j} (s_i - x) \\frac{r^{j-i}}{(j-i)!},

which for one stage is :math:`s_1 \\leftarrow s_1 + a (x - s_1)`,
:math:`a = 1 - e^{-r}`. It holds for any step, so irregular sampling needs no
resampling; rows sharing a time stamp still count as samples ``min_dt`` apart.
Every update is a convex combination of ``x`` and the old states, so the output
stays within the input's range. The state starts at the first used sample.
Holding the input over a step makes the output lead by up to one step on a
changing signal. The default ``min_dt`` of 20 ms is the Myo's sample period:
new samples arrive ~24 ms apart, two of them often in one burst with a single
time stamp.

A causal filter delays the envelope (about ``stages * tau``). A live stream can
only be filtered causally: each output may depend only on rows received so far,
so test streams use ``"causal"``. Training demonstrations are complete
recordings, so they may be filtered forward and then backward in time
(zero-phase: no delay, a symmetric pulse keeps its peak time); that looks ahead
and must never be applied to a stream a model is tested on.

Consecutive envelope samples at ~100 rows/s are strongly correlated; a model
that treats observations as independent would count them many times over.
``"causal"`` therefore keeps at most one output per ``1 / rate_hz`` s (30 Hz,
the tracker's frame rate).

EMG amplitude normalisation is NOT done here: it is fitted on the training
demonstrations only and stored in the model (elsewhere), so that a test stream
is scaled with training statistics.
"""

from __future__ import annotations

from collections import deque
from math import factorial

import numpy as np
from numpy.typing import ArrayLike

from sandbox.validation import FloatArray, check_array, check_choice, check_positive

#: Preprocessing modes of :func:`preprocess_signal`.
MODES = ("none", "causal", "smooth")
#: Filters of :func:`preprocess_signal` (a spec's ``modalities.NAME.preprocess``): the
#: first, what EMG needs, is the default.
FILTERS = ("envelope", "lowpass", "none")


def _check_times(times: ArrayLike) -> FloatArray:
    """Finite, non-decreasing 1-D times (s); the error names the first decrease."""
    t = check_array(times, "times", 1)
    bad = np.flatnonzero(np.diff(t) < 0)
    if bad.size:
        k = int(bad[0])
        raise ValueError(
            f"times: expected non-decreasing times, got t[{k}]={t[k]:g} "
            f"followed by t[{k + 1}]={t[k + 1]:g}"
        )
    return t


def _check_values(values: ArrayLike, n_rows: int | None = None) -> FloatArray:
    """Samples, shape (T, C), C >= 1; NaN allowed, infinity refused."""
    x = check_array(values, "values", 2, shape=(n_rows, None), allow_nan=True)
    if x.shape[1] < 1:
        raise ValueError(f"values: expected at least 1 channel, got shape {x.shape}")
    return x


def _check_mask(mask: ArrayLike, name: str, n_rows: int) -> np.ndarray:
    """A boolean row mask, shape (T,), as a new array."""
    m = np.array(mask, copy=True)
    if m.dtype != bool or m.shape != (n_rows,):
        want = f"a boolean array of shape ({n_rows},)"
        raise ValueError(f"{name}: expected {want}, got {m.dtype} array of shape {m.shape}")
    return m


def _check_filter(cutoff_hz: float, stages: int, min_dt: float) -> tuple[float, int, float]:
    """Time constant ``tau`` (s), number of stages and ``min_dt`` (s), checked."""
    if isinstance(stages, bool) or not isinstance(stages, int | np.integer) or stages < 1:
        raise ValueError(f"stages: expected an integer >= 1, got {stages!r}")
    tau = 1.0 / (2.0 * np.pi * check_positive(cutoff_hz, "cutoff_hz"))
    return tau, int(stages), check_positive(min_dt, "min_dt")


def rectify(values: ArrayLike) -> FloatArray:
    """Full-wave rectification ``|x|``, shape (T, C) -> (T, C); NaN stays NaN.

    The recorded Myo values are already non-negative, so it leaves them unchanged.
    """
    return np.abs(_check_values(values))


def fresh_rows(values: ArrayLike, repeat_window: int = 8) -> np.ndarray:
    """Rows of ``values`` (T, C) that carry a new sample, bool shape (T,).

    A row is fresh if all its channels are finite, they are not all exactly
    zero, and it repeats none of the last ``repeat_window`` fresh samples: the
    recorded stream re-sends samples, and not only the last one (a third of
    the rows that differ from their predecessor repeat the sample before it,
    A, B, A; the new ones arrive ~24 ms apart, the Myo's 50 Hz).
    """
    x = _check_values(values)
    if int(repeat_window) != repeat_window or repeat_window < 1:
        raise ValueError(f"repeat_window: expected an integer >= 1, got {repeat_window!r}")
    ok = np.isfinite(x).all(axis=1) & ~np.all(x == 0.0, axis=1)
    fresh = np.zeros(x.shape[0], dtype=bool)
    recent: deque[bytes] = deque(maxlen=int(repeat_window))
    for i in np.flatnonzero(ok):
        key = x[i].tobytes()
        if key not in recent:
            fresh[i] = True
            recent.append(key)
    return fresh


def _cascade(t: FloatArray, x: FloatArray, tau: float, stages: int, min_dt: float) -> FloatArray:
    """Causal cascade over used samples ``x`` (N, C) at times ``t`` (N,): last stage (N, C)."""
    out = np.empty_like(x)
    if x.shape[0] == 0:
        return out
    fact = np.array([factorial(m) for m in range(stages)], dtype=float)
    s = np.repeat(x[:1], stages, axis=0)  # state (stages, C), starts at the first sample
    out[0] = x[0]
    for k in range(1, x.shape[0]):
        dt = t[k] - t[k - 1]
        r = (dt if dt > 0 else min_dt) / tau
        d = s - x[k]
        # s_j <- x + exp(-r) sum_i (s_i - x) r^(j-i) / (j-i)!  (exact, input held at x)
        w = np.exp(-r) * r ** np.arange(stages) / fact
        s = x[k] + np.array([w[j::-1] @ d[: j + 1] for j in range(stages)])
        out[k] = s[-1]
    return out


def envelope(
    times: ArrayLike,
    values: ArrayLike,
    *,
    cutoff_hz: float = 5.0,
    causal: bool = True,
    stages: int = 2,
    min_dt: float = 0.02,
    use: ArrayLike | None = None,
) -> FloatArray:
    """Low-pass envelope of (already rectified) samples, see the module docstring.

    Parameters
    ----------
    times : array_like, shape (T,)
        Row times (s), non-decreasing (equal times allowed).
    values : array_like, shape (T, C)
        Samples (e.g. rectified EMG, raw units), NaN where missing.
    cutoff_hz : float
        Cut-off frequency (Hz) of each stage: ``tau = 1 / (2 pi cutoff_hz)``.
    causal : bool
        True: each output depends only on rows up to it. False: zero-phase
        (forward, then backward in time over the forward output); offline only.
    stages : int
        Number of cascaded first-order stages.
    min_dt : float
        Step (s) given to a used sample sharing the previous one's time stamp.
    use : array_like of bool, shape (T,), optional
        Rows that feed the filter; default :func:`fresh_rows`. Rows with a NaN
        are never used.

    Returns
    -------
    ndarray, shape (T, C)
        Envelope (units of ``values``); an unused row holds the previous used
        row's value, rows before the first used row are NaN.
    """
    t = _check_times(times)
    x = _check_values(values, t.size)
    tau, n, dt = _check_filter(cutoff_hz, stages, min_dt)
    used = fresh_rows(x) if use is None else _check_mask(use, "use", t.size)
    idx = np.flatnonzero(used & np.isfinite(x).all(axis=1))
    y = _cascade(t[idx], x[idx], tau, n, dt)
    if not causal:
        y = _cascade(-t[idx][::-1], y[::-1], tau, n, dt)[::-1]
    out = np.full(x.shape, np.nan)
    if idx.size:
        last = np.searchsorted(idx, np.arange(t.size), side="right") - 1
        out[last >= 0] = y[last[last >= 0]]
    return out


def decimate(times: ArrayLike, keep: ArrayLike, rate_hz: float) -> np.ndarray:
    """Keep at most one row per ``1 / rate_hz`` s, causally, bool shape (T,).

    Walking forward over ``times`` (s, shape (T,), non-decreasing), a row of
    ``keep`` (bool, shape (T,)) is kept if it is at least ``1 / rate_hz - 1e-9``
    s after the last kept row; the result is a subset of ``keep``.
    """
    t = _check_times(times)
    cand = _check_mask(keep, "keep", t.size)
    period = 1.0 / check_positive(rate_hz, "rate_hz") - 1e-9
    out = np.zeros(t.size, dtype=bool)
    last = -np.inf
    for k in np.flatnonzero(cand):
        if t[k] - last >= period:
            out[k], last = True, t[k]
    return out


def _filtered(t: FloatArray, x: FloatArray, fresh: np.ndarray, mode: str, filter: str,
              rate_hz: float, options: dict) -> tuple[FloatArray, np.ndarray]:
    """The output (T, C) and measured rows (T,) of :func:`preprocess_signal`."""
    if mode == "none":
        return x.copy(), fresh
    measured = decimate(t, fresh, rate_hz) if mode == "causal" else fresh
    if filter == "none":
        out = _held(x, fresh)
    else:
        source = rectify(x) if filter == "envelope" else x
        out = envelope(t, source, causal=mode == "causal", use=fresh, **options)
    if mode == "causal":
        out[~measured] = np.nan
    return out, measured


def _held(x: FloatArray, fresh: np.ndarray) -> FloatArray:
    """Each row's last new sample (rows before the first are NaN), shape of ``x``."""
    idx = np.flatnonzero(fresh)
    out = np.full(x.shape, np.nan)
    if idx.size:
        last = np.searchsorted(idx, np.arange(x.shape[0]), side="right") - 1
        out[last >= 0] = x[idx[last[last >= 0]]]
    return out


def _counts(x: FloatArray, fresh: np.ndarray, out: FloatArray) -> dict:
    """JSON-ready row counts of a signal and its preprocessed output."""
    missing = ~np.isfinite(x).all(axis=1)
    xf = x[fresh]
    constant = bool(xf.shape[0] < 2 or np.any(np.all(xf == xf[:1], axis=0)))
    return {
        "signal_fresh_rows": int(fresh.sum()),
        "signal_output_rows": int(np.isfinite(out).all(axis=1).sum()),
        "signal_zero_rows": int((~missing & np.all(x == 0.0, axis=1)).sum()),
        "signal_missing_rows": int(missing.sum()),
        "signal_constant": constant,
    }


def preprocess_signal(
    times: ArrayLike,
    values: ArrayLike,
    mode: str,
    *,
    cutoff_hz: float = 5.0,
    rate_hz: float = 30.0,
    stages: int = 2,
    min_dt: float = 0.02,
    filter: str = "envelope",
) -> tuple[FloatArray, np.ndarray, dict]:
    """Preprocess a signal column group for training (``"smooth"``) or a live stream (``"causal"``).

    Parameters
    ----------
    times, values : array_like, shapes (T,) and (T, C)
        Row times (s), non-decreasing, and raw samples, NaN where missing.
    mode : {"none", "causal", "smooth"}
        See the module docstring.
    cutoff_hz, stages, min_dt
        Envelope settings (:func:`envelope`).
    rate_hz : float
        Highest output rate of ``"causal"`` (Hz, :func:`decimate`).
    filter : {"envelope", "lowpass", "none"}
        What ``"causal"`` and ``"smooth"`` do to the values: ``envelope``
        (default, for EMG) rectifies them, then low-pass filters them;
        ``lowpass`` filters without rectifying (a signed force or torque keeps
        its sign); ``none`` keeps the values (``"smooth"``: held from the last
        new sample; ``"causal"``: the decimated new samples).

    Returns
    -------
    out : ndarray, shape (T, C)
        Preprocessed signal (units of ``values``).
    measured : ndarray of bool, shape (T,)
        Rows whose output is a measurement: fresh rows (``"none"``, ``"smooth"``),
        decimated fresh rows (``"causal"``).
    counts : dict
        ``signal_fresh_rows``, ``signal_output_rows`` (rows with a finite output),
        ``signal_zero_rows``, ``signal_missing_rows`` (rows with a NaN) and
        ``signal_constant`` (some channel identical over all fresh rows, or fewer
        than 2 fresh rows).
    """
    t = _check_times(times)
    x = _check_values(values, t.size)
    check_choice(mode, "mode", MODES)
    check_choice(filter, "filter", FILTERS)
    check_positive(rate_hz, "rate_hz")
    _check_filter(cutoff_hz, stages, min_dt)
    options = {"cutoff_hz": cutoff_hz, "stages": stages, "min_dt": min_dt}
    fresh = fresh_rows(x)
    out, measured = _filtered(t, x, fresh, mode, filter, rate_hz, options)
    return out, measured, _counts(x, fresh, out)
