"""A position track's jitter: the standard deviation of its sample-to-sample noise.

The observation noise floor of a position modality (:class:`~sandbox.core.model.IProMP`,
``jitter_floor``) can be taken from the data's own jitter instead of a constant
tuned for one tracker (2 cm suits a Kinect-class skeleton tracker; motion
capture has about 1 mm). This module estimates that jitter from the samples
of the training demonstrations, numpy only.

Derivation. Let a track be a smooth motion :math:`m(t)` plus white noise of
standard deviation :math:`\\sigma`, sampled at :math:`t_{i-1} < t_i < t_{i+1}`.
The residual of the middle sample from the straight line through its two
neighbours,

.. math::

    r_i = y_i - (b\\, y_{i-1} + a\\, y_{i+1}), \\qquad
    a = \\frac{t_i - t_{i-1}}{t_{i+1} - t_{i-1}},\\; b = 1 - a,

removes the motion up to its curvature (:math:`|r_i^{motion}| \\le \\tfrac12
\\max|m''|\\, \\Delta t^2`: 0.1 mm at 100 Hz for a hand accelerating at 2 m/s²)
and keeps the noise with variance :math:`\\sigma^2 (1 + a^2 + b^2)`. So
:math:`r_i / \\sqrt{1 + a^2 + b^2}` has standard deviation :math:`\\sigma`; for
evenly spaced samples this is the classic :math:`\\mathrm{std}(\\Delta^2 y)/\\sqrt 6`.
The estimate is robust: the median absolute value of the normalised residuals
times 1.4826 (the standard deviation of a Gaussian with that median absolute
value), so tracker jumps, frozen frames and dropouts (a few per cent of the
samples) do not inflate it. Missing (NaN) samples are skipped: a triple uses
consecutive *valid* samples. Samples that repeat their predecessor exactly (a
tracker re-sending its last frame) are dropped first, since they carry no new
measurement.
"""

from __future__ import annotations

import numpy as np

from sandbox.validation import FloatArray

#: Median absolute deviation -> standard deviation of a Gaussian.
MAD_TO_STD = 1.4826
#: Fewest normalised residuals an estimate is made from (fewer: no estimate, NaN).
MIN_RESIDUALS = 5
#: k, the default ``jitter_floor``: a position modality's noise floor is
#: ``max(noise_floor, k x jitter)``. The floor stands for what the model cannot explain
#: of a live track, which grows with the tracker's noise but is many times it. Measured
#: (leave-one-out, hand, dow_t 0.2 s; e_p m / recognition) on the recorded handovers
#: (jitter 1.35 mm), the motion-capture fixture (~1 mm) and synthetic sessions objects 1,
#: diverging 3 and 8 (2.1-2.3 mm), with the 2 cm minimum: k = 10 leaves every set as
#: the constant does; k = 15 leaves the first two and improves the synthetic ones
#: (.034/.38 -> .031/.43, .044/.93 -> .035/.94, .035/.91 -> .033/.93); k = 25 improves
#: them further but costs the recorded set 0.04 of recognition (.77 -> .73).
JITTER_FACTOR = 15.0


def residuals(times: FloatArray, values: FloatArray) -> FloatArray:
    """Normalised three-point residuals of one dim's fresh valid samples (module docstring).

    Parameters
    ----------
    times : ndarray, shape (T,)
        Seconds, increasing.
    values : ndarray, shape (T,)
        One dim of a position track (m), NaN where missing.

    Returns
    -------
    ndarray, shape (n,)
        :math:`r_i / \\sqrt{1 + a^2 + b^2}` for every run of three consecutive
        fresh, valid samples (m); empty when there are fewer than three.
    """
    t = np.asarray(times, dtype=np.float64)
    y = np.asarray(values, dtype=np.float64)
    if t.ndim != 1 or y.shape != t.shape:
        raise ValueError(f"values: expected shape {t.shape} (one per time), got {y.shape}")
    ok = np.isfinite(y) & np.isfinite(t)
    t, y = t[ok], y[ok]
    if y.size < 3:
        return np.empty(0)
    fresh = np.r_[True, np.diff(y) != 0.0]           # a re-sent frame is no new sample
    t, y = t[fresh], y[fresh]
    if y.size < 3:
        return np.empty(0)
    span = t[2:] - t[:-2]
    a = (t[1:-1] - t[:-2]) / np.where(span > 0, span, 1.0)
    b = 1.0 - a
    r = y[1:-1] - (b * y[:-2] + a * y[2:])
    return (r / np.sqrt(1.0 + a**2 + b**2))[span > 0]


def jitter(times: FloatArray, values: FloatArray) -> FloatArray:
    """Jitter (standard deviation of the noise) of each dim of a position track.

    Parameters
    ----------
    times : ndarray, shape (T,)
        Seconds, increasing.
    values : ndarray, shape (T, P)
        A position track (m), NaN where missing.

    Returns
    -------
    ndarray, shape (P,)
        Robust estimate per dim (m); NaN for a dim with fewer than
        :data:`MIN_RESIDUALS` residuals.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> t = np.arange(0, 3, 0.01)
    >>> track = np.c_[np.sin(t), np.cos(t)] + rng.normal(0, 0.001, (t.size, 2))
    >>> np.round(jitter(t, track) * 1000, 1)        # mm
    array([1., 1.])
    """
    values = np.asarray(values, dtype=np.float64)
    return np.array([pooled_jitter([residuals(times, values[:, j])])
                     for j in range(values.shape[1])])


def pooled_jitter(parts) -> float:
    """One jitter estimate (m) from the residuals of several tracks (:func:`residuals`)."""
    r = np.concatenate([np.asarray(p, dtype=np.float64).ravel() for p in parts]
                       or [np.empty(0)])
    if r.size < MIN_RESIDUALS:
        return float("nan")
    return float(MAD_TO_STD * np.median(np.abs(r)))


def track_jitter(times: FloatArray, values: FloatArray, accepted=None) -> float | None:
    """One jitter (m) pooled over the dims of a position track; None if too few samples.

    Parameters
    ----------
    times : ndarray, shape (T,)
    values : ndarray, shape (T, P)
        Raw (unfiltered) positions (m), NaN where missing.
    accepted : ndarray of bool, shape (T,), optional
        Rows to use (e.g. the tracker frames a glitch filter accepted); default all.
    """
    values = np.asarray(values, dtype=np.float64)
    if accepted is not None:
        keep = np.asarray(accepted, dtype=bool)
        times, values = np.asarray(times)[keep], values[keep]
    value = pooled_jitter([residuals(times, values[:, j]) for j in range(values.shape[1])])
    return None if not np.isfinite(value) else value


def demo_jitter(demo, times: FloatArray, human: FloatArray, modalities) -> FloatArray:
    """Jitter (m) of each human dim of one demonstration, shape (P,); NaN for signals.

    A position modality's jitter is the one the demonstration reports for its raw
    samples (``demo.jitter``, a mapping name -> m, as the data loaders record it
    before any filter), else it is estimated from ``human`` itself (right for
    unfiltered demonstrations; a smoothed track shows almost none).
    """
    given = getattr(demo, "jitter", None) or {}
    out, start = [], 0
    for m in modalities:
        value = float("nan")
        if m.kind == "position":
            raw = given.get(m.name)
            if raw is None:
                raw = track_jitter(times, human[:, start:start + m.size])
            value = float("nan") if raw is None else float(raw)
        out += [value] * m.size
        start += m.size
    return np.array(out)


def jitter_floors(jitters: FloatArray, modalities, factor: float, minimum: float,
                  default: FloatArray) -> FloatArray:
    """Noise floor of each human dim from the demos' jitter, shape (P,).

    Parameters
    ----------
    jitters : ndarray, shape (n_demos, P)
        Per demo (:func:`demo_jitter`), NaN where unknown.
    modalities : sequence of Modality
    factor : float
        k: a position dim's floor is ``max(minimum, k * median jitter over demos)``.
    minimum : float
        The documented lowest floor (m).
    default : ndarray, shape (P,)
        The floors used where no jitter is known (signals, or no estimate).
    """
    jitters = np.asarray(jitters, dtype=np.float64)
    known = np.isfinite(jitters).any(axis=0)
    median = np.full(jitters.shape[1], np.nan)
    median[known] = np.nanmedian(jitters[:, known], axis=0)
    kinds = np.array([m.kind == "position" for m in modalities for _ in range(m.size)])
    use = kinds & np.isfinite(median)
    return np.where(use, np.maximum(minimum, factor * np.where(use, median, 0.0)), default)
