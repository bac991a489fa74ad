"""A model of the skeleton tracker's artefacts, applied to a clean hand motion.

Measured on the recorded BIRL handovers (174 trials): the tracker delivers
~30 skeleton frames per second that are repeated on ~100 Hz rows
(sample-and-hold steps); between frames the hand jitters by ~1-2 mm; once rows
with a repeated timestamp are dropped, 74 % of trials contain jumps of 5 cm or
more between rows: ~1.5 excursions per trial away from the true path, mostly in
x and z, 5-13 cm, lasting 0.08 s (median; 90th percentile 0.3 s), from ~20 %
of the motion on, median at 65 %. That set has no (0, 0, 0) or missing rows, but other
recordings of this kind do, so both are available and off by default.

All artefacts are switchable through :class:`TrackerModel`; ``TrackerModel.clean()``
turns every one off.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sandbox.core.validation import FloatArray, check_positive


@dataclass(frozen=True)
class TrackerModel:
    """Which tracker artefacts to add, and how strong.

    Parameters
    ----------
    noise_m : float
        Standard deviation (m) of white noise per skeleton frame (0: none).
    frame_hz : float or None
        Skeleton frame rate (Hz): each row repeats the latest frame
        (sample-and-hold). ``None``: every row is a fresh frame.
    glitch_rate : float
        Mean number (Poisson) of jump episodes per demonstration (0: none).
    glitch_m : tuple of float
        Range (m) of a jump's size (uniform).
    glitch_s : float
        Median duration (s) of a jump episode (log-normal, sigma 0.9, at least
        one frame).
    glitch_phase : tuple of float
        Range of the phase (fraction of the duration) where episodes start.
    dropout_rate : float
        Probability that a frame is lost: its rows are NaN.
    zero_rate : float
        Probability that a frame reports (0, 0, 0) (person lost).
    """

    noise_m: float = 0.002
    frame_hz: float | None = 30.0
    glitch_rate: float = 1.6
    glitch_m: tuple[float, float] = (0.05, 0.14)
    glitch_s: float = 0.07
    glitch_phase: tuple[float, float] = (0.2, 1.0)
    dropout_rate: float = 0.0
    zero_rate: float = 0.0

    def __post_init__(self) -> None:
        check_positive(self.noise_m, "noise_m", allow_zero=True)
        if self.frame_hz is not None:
            check_positive(self.frame_hz, "frame_hz")
        check_positive(self.glitch_rate, "glitch_rate", allow_zero=True)
        check_positive(self.glitch_s, "glitch_s")
        lo, hi = self.glitch_m
        if not 0 < lo <= hi:
            raise ValueError(f"glitch_m: expected 0 < low <= high (m), got {self.glitch_m!r}")
        lo, hi = self.glitch_phase
        if not 0 <= lo <= hi <= 1:
            raise ValueError(f"glitch_phase: expected 0 <= low <= high <= 1, got {(lo, hi)!r}")
        for name in ("dropout_rate", "zero_rate"):
            value = check_positive(getattr(self, name), name, allow_zero=True)
            if value >= 1:
                raise ValueError(f"{name}: expected a probability in [0, 1), got {value!r}")

    @classmethod
    def clean(cls) -> TrackerModel:
        """A tracker without any artefact (the clean motion sampled on every row)."""
        return cls(noise_m=0.0, frame_hz=None, glitch_rate=0.0)


def frame_index(times: FloatArray, frame_hz: float | None, rng: np.random.Generator) -> FloatArray:
    """Index of the row whose sample each row shows (sample-and-hold), shape (T,).

    Frames are captured every ``1 / frame_hz`` s (+/- 20 % jitter, random
    phase); a row shows the latest frame captured at or before it.
    """
    n = times.size
    if frame_hz is None:
        return np.arange(n)
    period = 1.0 / frame_hz
    n_frames = int(np.ceil((times[-1] - times[0]) / period)) + 2
    steps = period * rng.uniform(0.8, 1.2, n_frames)
    capture = times[0] + rng.uniform(0.0, period) + np.r_[0.0, np.cumsum(steps[:-1])]
    # The row at which each frame becomes visible; the first row always shows a frame.
    first_row = np.searchsorted(times, capture, side="left")
    shown = np.zeros(n, dtype=int)
    shown[first_row[first_row < n]] = 1
    shown[0] = 1
    starts = np.flatnonzero(shown)
    return starts[np.cumsum(shown) - 1]


def _glitch_offsets(
    times: FloatArray, model: TrackerModel, rng: np.random.Generator
) -> FloatArray:
    """Offsets (m) of the jump episodes at each row, shape (T, 3)."""
    out = np.zeros((times.size, 3))
    n_episodes = rng.poisson(model.glitch_rate) if model.glitch_rate > 0 else 0
    span = times[-1] - times[0]
    min_s = 1.0 / model.frame_hz if model.frame_hz else 0.0
    for _ in range(n_episodes):
        start = times[0] + span * rng.uniform(*model.glitch_phase)
        length = max(min_s, model.glitch_s * rng.lognormal(0.0, 0.9))
        direction = rng.normal(size=3) * np.array([1.0, 0.4, 1.0])
        size = rng.uniform(*model.glitch_m)
        sel = (times >= start) & (times < start + length)
        out[sel] += size * direction / np.linalg.norm(direction)
    return out


def apply_tracker(
    times: FloatArray, clean: FloatArray, model: TrackerModel, rng: np.random.Generator
) -> FloatArray:
    """What the tracker reports for a clean hand motion.

    Parameters
    ----------
    times : ndarray, shape (T,)
        Row times (s), strictly increasing.
    clean : ndarray, shape (T, 3)
        True hand positions (m).
    model : TrackerModel
        The artefacts to add.
    rng : numpy.random.Generator
        Source of randomness.

    Returns
    -------
    ndarray, shape (T, 3)
        Reported positions (m); NaN rows are dropouts, (0, 0, 0) rows lost frames.
    """
    frames = clean + rng.normal(0.0, model.noise_m, clean.shape) if model.noise_m else clean.copy()
    frames = frames + _glitch_offsets(times, model, rng)
    shown = frame_index(times, model.frame_hz, rng)
    lost = rng.uniform(size=times.size) < model.dropout_rate
    zero = rng.uniform(size=times.size) < model.zero_rate
    frames[lost] = np.nan
    frames[zero & ~lost] = 0.0
    return frames[shown]
