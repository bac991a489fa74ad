"""A model of the skeleton tracker's artefacts, applied to a clean hand and arm motion.

Measured on the recorded BIRL handovers (174 trials): the tracker delivers
~30 skeleton frames per second that are repeated on ~100 Hz rows
(sample-and-hold steps); between frames the hand jitters by ~1-2 mm; once rows
with a repeated timestamp are dropped, 74 % of trials contain jumps of 5 cm or
more between rows: ~1.5 excursions per trial away from the true path, mostly in
x and z, 5-13 cm, lasting 0.08 s (median; 90th percentile 0.3 s), from ~20 %
of the motion on, median at 65 %. That set has no (0, 0, 0) or missing rows, but other
recordings of this kind do, so both are available and off by default.

The whole skeleton shares one frame schedule (:class:`FrameSchedule`): the
hand, elbow and shoulder step on the same rows (99 % of the recorded rows agree)
and a lost frame loses them all. The elbow jitters like the hand (~2 mm) and
jumps nearly as often (433 jumps of 5 cm+ between rows vs the hand's 516; 230
of them on the same rows as the hand's); the shoulder jitters ~1 mm and never
jumps (:func:`track_arm`).

All artefacts are switchable through :class:`TrackerModel`; ``TrackerModel.clean()``
turns every one off.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sandbox.limits import BOUNDS
from sandbox.validation import FloatArray, check_positive


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
    elbow_shared : float
        Probability that the elbow jumps too in one of the hand's episodes
        (its own offset, the same rows).
    elbow_own : float
        Rate of the elbow's own episodes, as a fraction of ``glitch_rate``.
    shoulder_noise : float
        The shoulder's jitter, as a fraction of ``noise_m``.
    """

    noise_m: float = 0.002
    frame_hz: float | None = 30.0
    glitch_rate: float = 1.6
    glitch_m: tuple[float, float] = (0.05, 0.14)
    glitch_s: float = 0.07
    glitch_phase: tuple[float, float] = (0.2, 1.0)
    dropout_rate: float = 0.0
    zero_rate: float = 0.0
    elbow_shared: float = 0.45
    elbow_own: float = 0.4
    shoulder_noise: float = 0.4

    def __post_init__(self) -> None:
        for name in ("noise_m", "glitch_rate", "frame_hz"):   # the one table of limits
            if getattr(self, name) is not None or name != "frame_hz":
                BOUNDS[name].check(getattr(self, name), name)
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
        if not 0 <= check_positive(self.elbow_shared, "elbow_shared", allow_zero=True) <= 1:
            raise ValueError(f"elbow_shared: expected a probability in [0, 1], "
                             f"got {self.elbow_shared!r}")
        check_positive(self.elbow_own, "elbow_own", allow_zero=True)
        check_positive(self.shoulder_noise, "shoulder_noise", allow_zero=True)

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


@dataclass(frozen=True)
class FrameSchedule:
    """What the tracker did on each row: shared by every joint of the skeleton.

    Attributes
    ----------
    shown : ndarray of int, shape (T,)
        Index of the row whose frame each row repeats (:func:`frame_index`).
    lost : ndarray of bool, shape (T,)
        Rows whose frame was lost (reported as NaN, the whole skeleton).
    zero : ndarray of bool, shape (T,)
        Rows whose frame reported (0, 0, 0) (person lost), not ``lost``.
    episodes : tuple of (float, float)
        Start and duration (s) of the hand's jump episodes.
    """

    shown: np.ndarray
    lost: np.ndarray
    zero: np.ndarray
    episodes: tuple[tuple[float, float], ...]

    def show(self, frames: FloatArray) -> FloatArray:
        """What the rows report of per-row ``frames`` (T, k): losses, zeros, sample-and-hold."""
        out = np.array(frames, dtype=float)
        out[self.lost] = np.nan
        out[self.zero] = 0.0
        return out[self.shown]


def _episode_offset(model: TrackerModel, rng: np.random.Generator) -> FloatArray:
    """One jump's offset (m), shape (3,): mostly in x and z, size uniform in ``glitch_m``."""
    direction = rng.normal(size=3) * np.array([1.0, 0.4, 1.0])
    size = rng.uniform(*model.glitch_m)
    return size * direction / np.linalg.norm(direction)


def _glitch_episodes(
    times: FloatArray, model: TrackerModel, rng: np.random.Generator, rate: float
) -> list[tuple[float, float, FloatArray]]:
    """Jump episodes ``(start s, duration s, offset m (3,))``, Poisson(``rate``) of them."""
    n_episodes = rng.poisson(rate) if rate > 0 else 0
    span = times[-1] - times[0]
    min_s = 1.0 / model.frame_hz if model.frame_hz else 0.0
    episodes = []
    for _ in range(n_episodes):
        start = times[0] + span * rng.uniform(*model.glitch_phase)
        length = max(min_s, model.glitch_s * rng.lognormal(0.0, 0.9))
        episodes.append((start, length, _episode_offset(model, rng)))
    return episodes


def _offsets(times: FloatArray, episodes: list[tuple[float, float, FloatArray]]) -> FloatArray:
    """Summed offsets (m) of ``episodes`` at each row, shape (T, 3)."""
    out = np.zeros((times.size, 3))
    for start, length, offset in episodes:
        out[(times >= start) & (times < start + length)] += offset
    return out


def _jitter(shape: tuple[int, ...], noise_m: float, rng: np.random.Generator) -> FloatArray:
    return rng.normal(0.0, noise_m, shape) if noise_m else np.zeros(shape)


def track_hand(
    times: FloatArray, clean: FloatArray, model: TrackerModel, rng: np.random.Generator
) -> tuple[FloatArray, FrameSchedule]:
    """What the tracker reports for a clean hand motion, and its frame schedule.

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
    human : ndarray, shape (T, 3)
        Reported positions (m); NaN rows are dropouts, (0, 0, 0) rows lost frames.
    schedule : FrameSchedule
        Frames, losses and jump episodes, for :func:`track_arm`.
    """
    frames = clean + _jitter(clean.shape, model.noise_m, rng)
    episodes = _glitch_episodes(times, model, rng, model.glitch_rate)
    frames = frames + _offsets(times, episodes)
    shown = frame_index(times, model.frame_hz, rng)
    lost = rng.uniform(size=times.size) < model.dropout_rate
    zero = rng.uniform(size=times.size) < model.zero_rate
    schedule = FrameSchedule(shown, lost, zero & ~lost, tuple((s, n) for s, n, _ in episodes))
    return schedule.show(frames), schedule


def apply_tracker(
    times: FloatArray, clean: FloatArray, model: TrackerModel, rng: np.random.Generator
) -> FloatArray:
    """What the tracker reports for a clean hand motion, shape (T, 3) (see :func:`track_hand`)."""
    return track_hand(times, clean, model, rng)[0]


def track_arm(
    times: FloatArray,
    clean: FloatArray,
    model: TrackerModel,
    schedule: FrameSchedule,
    rng: np.random.Generator,
) -> FloatArray:
    """What the tracker reports for a clean arm, on the hand's frames.

    The rows repeat the same frames as the hand's and lose the same ones;
    the elbow jitters like the hand (``noise_m``) and the shoulder less
    (``shoulder_noise * noise_m``); the elbow jumps in a share
    (``elbow_shared``) of the hand's episodes and in its own (rate
    ``elbow_own * glitch_rate``); the shoulder does not jump.

    Parameters
    ----------
    times : ndarray, shape (T,)
        Row times (s), those of the hand.
    clean : ndarray, shape (T, 6)
        True elbow x, y, z and shoulder x, y, z (m).
    model : TrackerModel
        The artefacts (the hand's).
    schedule : FrameSchedule
        The hand's frame schedule (:func:`track_hand`).
    rng : numpy.random.Generator
        Source of the arm's own randomness (never the hand's generator).

    Returns
    -------
    ndarray, shape (T, 6)
        Reported positions (m), NaN and (0, 0, 0) on the hand's lost rows.
    """
    elbow = clean[:, :3] + _jitter((times.size, 3), model.noise_m, rng)
    shoulder = clean[:, 3:] + _jitter((times.size, 3), model.shoulder_noise * model.noise_m, rng)
    shared = [(start, length, _episode_offset(model, rng)) for start, length in schedule.episodes
              if rng.uniform() < model.elbow_shared]
    own = _glitch_episodes(times, model, rng, model.elbow_own * model.glitch_rate)
    elbow = elbow + _offsets(times, shared + own)
    return schedule.show(np.column_stack([elbow, shoulder]))
