"""Preprocessing of the human rows of a demonstration, modality by modality.

Every modality (:mod:`sandbox.core.modality`) is preprocessed by its kind, then
the rows are collapsed to one per time stamp (the last row of each):

``"position"`` (tracked points, m)
    Each point (three columns; a modality whose size is not a multiple of 3 is
    one track) goes through :func:`preprocess_rows`: glitch classification
    (:mod:`sandbox.data.glitches`), then by ``preprocess``

    ``"none"``
        the recorded values at the kept rows, untouched (stale and zero rows included).
    ``"causal"``
        the output of the gated Kalman filter (:mod:`sandbox.data.filtering`)
        at rows where a new frame was accepted, NaN elsewhere (stale, zero,
        missing and gated-out rows are marked, not invented). Each value only
        depends on earlier rows: use it for test streams.
    ``"smooth"`` (default)
        first, frames farther than ``excursion_m`` from the running median of the
        frames within +/- 0.25 s are set aside (the tracker's occlusion jumps,
        :func:`sandbox.data.glitches.excursions`; this looks at later frames);
        then the gated filter and the RTS smoother run on the remaining frames,
        and the smoothed track is given at every row that lies in a gap of at
        most ``max_fill_s`` (default 1 s) between accepted frames or at most
        0.1 s after the last one, NaN elsewhere. For training demos: a long
        gap left NaN makes a basis-function fit of the demo ill-posed there
        (weights of metres), a bridged one does not.

``"signal"`` (activity, raw units, e.g. EMG)
    :func:`sandbox.data.signals.preprocess_signal`: by default (``envelope``,
    what EMG needs) rectified, then a low-pass envelope, causal and thinned to
    ``signal_rate_hz`` for ``"causal"``, zero-phase at every row for
    ``"smooth"``; a spec's ``modalities.NAME.preprocess`` may choose
    ``lowpass`` (the same filter without rectifying: a signed force or torque
    keeps its sign) or ``none`` (the values as they come). Amplitude normalisation is not
    done here: the model fits it on its training demonstrations only.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from sandbox.core.jitter import track_jitter
from sandbox.core.modality import Modality, default_modalities
from sandbox.data.demonstration import Demonstration
from sandbox.data.filtering import FilterConfig, filter_track, smooth_track
from sandbox.data.glitches import excursions, find_glitches
from sandbox.data.signals import preprocess_signal
from sandbox.validation import FloatArray, check_choice, check_positive

PREPROCESS = ("none", "causal", "smooth")
#: Width (s) of the running-median window used to find excursions ("smooth").
EXCURSION_WINDOW_S = 0.5
#: "smooth" extrapolates past the last accepted frame by at most this (s).
MAX_EXTRAPOLATE_S = 0.1
#: Options of :func:`preprocess_human` and their defaults.
DEFAULTS: dict[str, Any] = {"config": None, "freeze_s": 0.25, "max_fill_s": 1.0, "jump_m": 0.05,
                            "excursion_m": 0.04, "signal_cutoff_hz": 5.0,
                            "signal_rate_hz": 30.0}


def _human_track(
    times: FloatArray, values: FloatArray, preprocess: str, config: Any, max_fill_s: float
) -> tuple[FloatArray, np.ndarray, dict[str, int]]:
    """Per-row human output, the rows whose frame was used, and filter counts."""
    run = filter_track(times, values, config)
    used = run.used
    counts = run.counts()
    stats = {"gate_rejected": counts["rejected"], "filter_resets": counts["reset"]}
    if preprocess == "causal":
        return run.filtered, used, stats
    smoothed = smooth_track(run)
    t_used = times[used]
    if t_used.size == 0:
        return smoothed, used, stats
    k = np.searchsorted(t_used, times, side="right")  # next used frame index
    prev = t_used[np.maximum(k - 1, 0)]
    inside = (k > 0) & (k < t_used.size)
    nxt = t_used[np.minimum(k, t_used.size - 1)]
    fill = inside & (nxt - prev <= max_fill_s)  # a gap bridged by the smoother
    fill |= (k == t_used.size) & (times - prev <= min(max_fill_s, MAX_EXTRAPOLATE_S))
    fill |= used
    return np.where(fill[:, None], smoothed, np.nan), used, stats


def preprocess_rows(
    times: FloatArray,
    human: FloatArray,
    preprocess: str,
    *,
    config: FilterConfig | None = None,
    freeze_s: float = 0.25,
    max_fill_s: float = 1.0,
    jump_m: float = 0.05,
    excursion_m: float = 0.04,
) -> tuple[FloatArray, np.ndarray, dict[str, int | float]]:
    """Classify and preprocess human rows, then keep one row per time stamp.

    Parameters
    ----------
    times : ndarray, shape (T,)
        Row times (s), non-decreasing; rows sharing a time stamp are collapsed
        to the last of them.
    human : ndarray, shape (T, P)
        Human values (m), NaN where missing.
    preprocess, config, freeze_s, max_fill_s, jump_m, excursion_m
        As in :func:`sandbox.data.recorded.load_trial`.

    Returns
    -------
    human : ndarray, shape (T', P)
        One row per distinct time stamp (see the module docstring for each mode).
    measured : ndarray of bool, shape (T',)
        Time stamps at which a new tracker frame was received (and, when
        filtering, accepted by the gate).
    counts : dict
        Glitch and filter counts (JSON-ready).
    """
    _check_position_options(preprocess, config=config, freeze_s=freeze_s,
                            max_fill_s=max_fill_s, jump_m=jump_m, excursion_m=excursion_m)
    glitches = find_glitches(times, human, freeze_s=freeze_s, jump_m=jump_m)
    measurement = np.where(glitches.fresh[:, None], human, np.nan)
    away = np.zeros(times.size, dtype=bool)
    if excursion_m > 0:
        away = excursions(times, measurement, window_s=EXCURSION_WINDOW_S, threshold_m=excursion_m)
    stats = {"excursions": int(away.sum()), "gate_rejected": 0, "filter_resets": 0}
    if preprocess == "none":
        out_rows, used = human, glitches.fresh
    else:
        if preprocess == "smooth":
            measurement[away] = np.nan  # set aside: offline only (the median sees ahead)
        out_rows, used, counts = _human_track(times, measurement, preprocess, config, max_fill_s)
        stats.update(counts)
    last = np.flatnonzero(np.r_[np.diff(times) > 0, True])
    group = np.cumsum(np.r_[True, np.diff(times) > 0]) - 1
    measured = np.bincount(group, weights=used.astype(float), minlength=last.size) > 0
    out = out_rows[last]
    if preprocess == "causal":
        out = np.where(measured[:, None], out, np.nan)
    unfilled = int(np.isnan(out).any(axis=1).sum())
    return out, measured, {**glitches.counts(), **stats, "unfilled_samples": unfilled}


def preprocess_human(
    times: FloatArray,
    human: FloatArray,
    modalities: Sequence[Modality],
    preprocess: str,
    *,
    signal_filters: dict[str, str] | None = None,
    **options: Any,
) -> tuple[FloatArray, np.ndarray, dict[str, dict]]:
    """Preprocess every modality by its kind and keep one row per time stamp.

    Parameters
    ----------
    times : ndarray, shape (T,)
        Row times (s), non-decreasing.
    human : ndarray, shape (T, P)
        The modalities' columns one after the other, NaN where missing.
    modalities : sequence of Modality
    preprocess : {"none", "causal", "smooth"}
    signal_filters : dict, optional
        Per signal modality name, its filter (:data:`sandbox.data.signals.FILTERS`:
        ``envelope``, the default, ``lowpass`` or ``none``; a spec's
        ``modalities.NAME.preprocess``).
    **options
        Those of :data:`DEFAULTS` (``config``, ``freeze_s``, ``max_fill_s``,
        ``jump_m``, ``excursion_m`` for positions; ``signal_cutoff_hz``,
        ``signal_rate_hz`` for signals).

    Returns
    -------
    human : ndarray, shape (T', P)
        One row per distinct time stamp.
    measured : ndarray of bool, shape (T', n_modalities)
        Time stamps at which each modality received a new (accepted) sample.
    counts : dict
        Per modality name, its glitch and filter counts (JSON-ready); a position
        modality's ``jitter_m`` is the jitter (m) of its raw frames, (0, 0, 0) rows left
        out (:func:`sandbox.core.jitter.track_jitter`, robust to the other glitches; the
        glitch filter's accepted frames would clip the noise of a noisy tracker at
        ``jump_m``; None if too few).
    """
    opts = check_options(preprocess, **options)
    position = {k: opts[k] for k in ("config", "freeze_s", "max_fill_s", "jump_m", "excursion_m")}
    last = np.flatnonzero(np.r_[np.diff(times) > 0, True])
    outs, measured, counts, start = [], [], {}, 0
    for m in modalities:
        cols = human[:, start:start + m.size]
        start += m.size
        if m.kind == "position":
            out, meas, c = _positions(times, cols, preprocess, position)
            raw = cols[last]                       # raw frames; (0, 0, 0) is no measurement
            c = {**c, "jitter_m": track_jitter(times[last], raw, ~(raw == 0).all(axis=1))}
        else:
            how = (signal_filters or {}).get(m.name, "envelope")
            out, meas, c = _signal(times, cols, preprocess, opts, last, how)
        outs.append(out)
        measured.append(meas)
        counts[m.name] = {**c, "measured_samples": int(meas.sum())}
    return np.hstack(outs), np.column_stack(measured), counts


def _positions(times, values, preprocess, options):
    """Each 3-D point through :func:`preprocess_rows`; counts summed over the points."""
    size = values.shape[1]
    width = 3 if size % 3 == 0 else size
    outs, measured, total = [], None, {}
    for j in range(0, size, width):
        out, meas, c = preprocess_rows(times, values[:, j:j + width], preprocess, **options)
        outs.append(out)
        measured = meas if measured is None else measured & meas
        for key, value in c.items():
            total[key] = total.get(key, 0) + value
    return np.hstack(outs), measured, total


def _signal(times, values, preprocess, opts, last, how="envelope"):
    out, meas, c = preprocess_signal(times, values, preprocess, cutoff_hz=opts["signal_cutoff_hz"],
                                     rate_hz=opts["signal_rate_hz"], filter=how)
    group = np.cumsum(np.r_[True, np.diff(times) > 0]) - 1
    finite = np.isfinite(out).all(axis=1)
    pick = last.copy()                  # per time stamp: its last row with an output, if any
    rows = np.flatnonzero(finite)
    pick[group[rows]] = rows            # later rows of a group overwrite earlier ones
    measured = np.bincount(group, weights=meas.astype(float), minlength=last.size) > 0
    collapsed = out[pick]
    if preprocess == "causal":
        collapsed = np.where(measured[:, None], collapsed, np.nan)
    return collapsed, measured, c


def _check_position_options(
    preprocess: str,
    *,
    config: Any,
    freeze_s: float,
    max_fill_s: float,
    jump_m: float,
    excursion_m: float,
) -> None:
    check_choice(preprocess, "preprocess", PREPROCESS)
    check_positive(freeze_s, "freeze_s")
    check_positive(max_fill_s, "max_fill_s", allow_zero=True)
    check_positive(jump_m, "jump_m")
    check_positive(excursion_m, "excursion_m", allow_zero=True)
    if config is not None and not isinstance(config, FilterConfig):
        raise ValueError(f"config: expected a FilterConfig, got {type(config).__name__}")


def check_options(preprocess: str, **options: Any) -> dict[str, Any]:
    """Validate preprocessing options; return them with defaults filled in."""
    check_choice(preprocess, "preprocess", PREPROCESS)
    unknown = sorted(set(options) - set(DEFAULTS))
    if unknown:
        raise ValueError(f"preprocessing options: unknown {unknown}; expected some of "
                         f"{sorted(DEFAULTS)}")
    opts = {**DEFAULTS, **options}
    _check_position_options(preprocess, **{k: opts[k] for k in
                                           ("config", "freeze_s", "max_fill_s", "jump_m",
                                            "excursion_m")})
    check_positive(opts["signal_cutoff_hz"], "signal_cutoff_hz")
    check_positive(opts["signal_rate_hz"], "signal_rate_hz")
    return opts


def preprocess_demonstration(
    demo: Demonstration, preprocess: str = "smooth", **options: Any
) -> Demonstration:
    """Apply the loader's human preprocessing to any demonstration (e.g. synthetic).

    ``options`` are those of :func:`preprocess_human`. The robot and the times are
    unchanged; ``meta["report"]`` gets the glitch and filter counts (those of
    the first modality at the top level, every modality's under ``"modalities"``),
    ``meta["modality_measured"]`` (T, n_modalities) the rows with an accepted
    new sample of each modality and ``meta["human_measured"]`` (T,) those of any.
    ``preprocess="none"`` returns ``demo`` itself.
    """
    check_options(preprocess, **options)
    if preprocess == "none":
        return demo
    mods = demo.modalities or default_modalities(demo.human_names)
    human, measured, counts = preprocess_human(demo.times, demo.human, mods, preprocess,
                                               **options)
    report = {**dict(demo.meta.get("report", {})), "preprocess": preprocess,
              **summary_counts(counts, mods)}
    return demo.replace(human=human, meta={**demo.meta, "report": report,
                                           **measured_meta(measured)})


def summary_counts(counts: dict[str, dict], modalities: Sequence[Modality]) -> dict:
    """Report entries: the first position modality's counts at the top level (the
    hand's, as the reports of single-modality sets always had), all under "modalities"."""
    first = next((counts[m.name] for m in modalities if m.kind == "position"),
                 counts[modalities[0].name])
    return {**first, "modalities": counts}


def measured_meta(measured: np.ndarray) -> dict[str, np.ndarray]:
    """``modality_measured`` (T, n) and ``human_measured`` (T,), read-only."""
    any_row = measured.any(axis=1)
    for a in (measured, any_row):
        a.setflags(write=False)
    return {"modality_measured": measured, "human_measured": any_row}
