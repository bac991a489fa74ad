"""Human-motion filter: a gated constant-velocity Kalman filter and an RTS smoother.

The only module that imports :mod:`filterpy`, where used (it pulls in :mod:`scipy.stats`).

Model (per hand coordinate, state ``x = [p, v]`` stacked as ``[p_1..p_P, v_1..v_P]``):

.. math::

    x_{k} = F(\\Delta t) x_{k-1} + w,\\quad w \\sim N(0, Q(\\Delta t)),\\qquad
    y_k = H x_k + e,\\quad e \\sim N(0, \\sigma_r^2 I)

with ``F = [[I, dt I], [0, I]]`` and ``Q`` the continuous white-acceleration noise
of spectral density ``q = accel_std**2`` (m^2 s^-3) integrated over ``dt``.

Innovation gating: a sample whose squared Mahalanobis distance
``d2 = nu^T S^-1 nu`` (``nu = y - H x_prior``, ``S = H P_prior H^T + R``) exceeds
the ``gate_prob`` quantile of a chi-square with P degrees of freedom is rejected
(not used). After ``max_rejects`` consecutive rejections the filter concludes
that the track itself has moved and re-initialises on the current sample.

:class:`HandFilter` is causal: its output at time t depends only on samples received up
to t. :func:`filter_track` runs it over a track, keeping what :func:`smooth_track` needs.
The defaults were measured on the 174 recorded handovers (:mod:`sandbox.data.filtercheck`).

Limits (measured): the gate is loose at these settings. On a 30 Hz constant-velocity
track (0.37 m/s, 3 mm noise) isolated spikes of 15 cm pass and of 20 cm are rejected
with the defaults; with ``accel_std=3`` 81 % of the 10 cm spikes are rejected, with
``accel_std=0.2`` (which a real reach does not allow) all 5 cm spikes. The recorded
tracker's 5 cm+ jumps are mostly multi-frame occlusion excursions near the handover; no
causal gate tells their first frames from a real fast motion, so the causal output
follows them. The offline ``"smooth"`` preprocessing of the loader sets them aside
first with a running median (:func:`sandbox.data.glitches.excursions`).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import gammaincinv

from sandbox.data import kalman
from sandbox.validation import FloatArray, check_array, check_fraction, check_positive

#: Per-sample status codes of :func:`filter_track` (index into :data:`STATUS_NAMES`).
WAITING, MISSING, ACCEPTED, REJECTED, INIT, RESET, STALE = range(7)
STATUS_NAMES = ("waiting", "missing", "accepted", "rejected", "init", "reset", "stale")


@dataclass(frozen=True)
class FilterConfig:
    """Noise figures and gate of the hand filter.

    Parameters
    ----------
    accel_std : float
        Square root of the white-acceleration spectral density (m s^-1.5); larger
        follows fast motion more closely, smaller smooths more.
    noise_std : float
        Standard deviation of the tracker's position noise per axis (m).
    gate_prob : float
        Probability mass of the chi-square gate (0.999 rejects a consistent
        sample once in a thousand).
    max_rejects : int
        Consecutive rejections after which the filter re-initialises on the
        current sample (the track has really moved).
    init_speed_std : float
        Prior standard deviation of the hand speed per axis at (re)initialisation (m/s).
    time_jitter_std : float
        Standard deviation of the error of a sample's time stamp (s). The recorded
        tracker frames arrive in bursts (two frames with one time stamp, then a
        gap), so a sample's stamp is not when the frame was taken: the sample is
        modelled as ``p(t + delta) + e ~ p(t) + v delta + e``, which adds
        ``time_jitter_std**2 * (v v^T + P_vv)`` to the measurement noise.
    """

    accel_std: float = 6.0
    noise_std: float = 0.003
    gate_prob: float = 0.999
    max_rejects: int = 5
    init_speed_std: float = 0.5
    time_jitter_std: float = 0.01

    def __post_init__(self) -> None:
        check_positive(self.accel_std, "accel_std")
        check_positive(self.noise_std, "noise_std")
        check_fraction(self.gate_prob, "gate_prob")
        check_positive(self.init_speed_std, "init_speed_std")
        check_positive(self.time_jitter_std, "time_jitter_std", allow_zero=True)
        if int(self.max_rejects) != self.max_rejects or self.max_rejects < 1:
            raise ValueError(f"max_rejects: expected an integer >= 1, got {self.max_rejects!r}")

    def gate(self, n_dims: int) -> float:
        """Threshold on the squared Mahalanobis distance for ``n_dims`` coordinates."""
        q = 2.0 * gammaincinv(n_dims / 2.0, self.gate_prob)   # = scipy.stats.chi2.ppf
        return float(q) if self.gate_prob < 1 else np.inf


def transition(dt: float, n_dims: int, config: FilterConfig) -> tuple[FloatArray, FloatArray]:
    """State transition ``F`` and process noise ``Q`` over ``dt`` seconds, shapes (2P, 2P)."""
    from filterpy.common import Q_continuous_white_noise
    F = np.eye(2 * n_dims)
    F[:n_dims, n_dims:] = dt * np.eye(n_dims)
    Q = Q_continuous_white_noise(
        dim=2, dt=dt, spectral_density=config.accel_std**2, block_size=n_dims,
        order_by_dim=False,
    )
    return F, np.asarray(Q, dtype=float)


class HandFilter:
    """Causal, gated constant-velocity Kalman filter for a P-D hand position stream.

    Feed samples in time order with :meth:`update`; each call returns the current
    position estimate (m). A sample with a NaN (tracker dropout) is not used: the
    filter only predicts. Irregular time steps are fine, equal times too (several
    samples at one instant are all used).

    Parameters
    ----------
    n_dims : int
        Number of position coordinates P (3 for a hand).
    config : FilterConfig, optional
        Noise figures and gate; defaults to ``FilterConfig()``.
    drop_repeats : bool
        Treat a sample exactly equal to one of the last ``repeat_window`` distinct
        samples as no new information (status "stale"): the recorded tracker
        re-sends old frames between new ones.
    zero_is_missing : bool
        Treat an all-zero sample as missing (the tracker's "person lost").
    repeat_window : int
        See ``drop_repeats``.

    Examples
    --------
    >>> f = HandFilter()
    >>> f.update(0.0, [1.0, 0.0, 0.2]).round(3).tolist()
    [1.0, 0.0, 0.2]
    >>> bool(np.isnan(f.update(0.03, [np.nan, np.nan, np.nan])).any())
    False
    """

    def __init__(
        self,
        n_dims: int = 3,
        config: FilterConfig | None = None,
        *,
        drop_repeats: bool = True,
        zero_is_missing: bool = True,
        repeat_window: int = 64,
    ) -> None:
        if int(n_dims) != n_dims or n_dims < 1:
            raise ValueError(f"n_dims: expected an integer >= 1, got {n_dims!r}")
        if config is not None and not isinstance(config, FilterConfig):
            raise ValueError(f"config: expected a FilterConfig, got {type(config).__name__}")
        self.n_dims = int(n_dims)
        self.config = config if config is not None else FilterConfig()
        self.drop_repeats = bool(drop_repeats)
        self.zero_is_missing = bool(zero_is_missing)
        self._recent: deque[bytes] = deque(maxlen=int(repeat_window))
        self._gate = self.config.gate(self.n_dims)
        from filterpy.kalman import KalmanFilter
        self._kf = KalmanFilter(dim_x=2 * self.n_dims, dim_z=self.n_dims)
        self._kf.H = np.hstack([np.eye(self.n_dims), np.zeros((self.n_dims, self.n_dims))])
        self._kf.R = self.config.noise_std**2 * np.eye(self.n_dims)
        self._time: float | None = None
        self._initialised = False
        self._rejects = 0
        self.status = WAITING
        self.last_d2 = np.nan
        self.last_F = np.eye(2 * self.n_dims)
        self.last_Q = np.zeros((2 * self.n_dims, 2 * self.n_dims))

    @property
    def initialised(self) -> bool:
        """True once a first sample has been accepted."""
        return self._initialised

    @property
    def position(self) -> FloatArray:
        """Current position estimate (m), shape (P,); NaN before the first sample."""
        if not self._initialised:
            return np.full(self.n_dims, np.nan)
        return self._kf.x[: self.n_dims, 0].copy()

    @property
    def velocity(self) -> FloatArray:
        """Current velocity estimate (m/s), shape (P,); NaN before the first sample."""
        if not self._initialised:
            return np.full(self.n_dims, np.nan)
        return self._kf.x[self.n_dims :, 0].copy()

    @property
    def state(self) -> tuple[FloatArray, FloatArray]:
        """Current state mean, shape (2P,), and covariance, shape (2P, 2P)."""
        return self._kf.x[:, 0].copy(), self._kf.P.copy()

    def update(self, t: float, y: ArrayLike) -> FloatArray:
        """Take the sample ``y`` (m, shape (P,)) received at time ``t`` (s).

        Returns the position estimate after the sample, shape (P,). ``self.status``
        tells what happened to the sample (:data:`STATUS_NAMES`). Raises
        ``ValueError`` if ``t`` is earlier than the previous sample's time.
        """
        t = float(t)
        if not np.isfinite(t):
            raise ValueError(f"t: expected a finite time (s), got {t!r}")
        y = check_array(y, "y", 1, shape=(self.n_dims,), allow_nan=True)
        if self._time is not None and t < self._time:
            raise ValueError(
                f"t: expected samples in time order, got t={t:g} after t={self._time:g}"
            )
        skip = self._classify(y)
        if not self._initialised:
            self._time = t
            if skip is None:
                self._initialise(y)
            self.status = INIT if skip is None else WAITING
            return self.position
        self._predict(t - self._time)
        self._time = t
        if skip is None:
            self._correct(y)
        else:
            self.status = skip
        return self.position

    def _classify(self, y: FloatArray) -> int | None:
        """MISSING or STALE if the sample carries no new information, else None."""
        if np.isnan(y).any() or (self.zero_is_missing and np.all(y == 0.0)):
            return MISSING
        if self.drop_repeats:
            key = y.tobytes()
            if key in self._recent:
                return STALE
            self._recent.append(key)
        return None

    def _initialise(self, y: FloatArray) -> None:
        p = self.n_dims
        self._kf.x = np.concatenate([y, np.zeros(p)])[:, None]
        self._kf.P = np.diag(
            np.r_[np.full(p, self.config.noise_std**2), np.full(p, self.config.init_speed_std**2)]
        )
        self._initialised = True
        self._rejects = 0

    def _predict(self, dt: float) -> None:
        F, Q = transition(dt, self.n_dims, self.config)
        self.last_F, self.last_Q = F, Q
        if dt > 0:
            self._kf.predict(F=F, Q=Q)

    def _correct(self, y: FloatArray) -> None:
        kf, p = self._kf, self.n_dims
        v = kf.x[p:, 0]
        R = kf.R + self.config.time_jitter_std**2 * (np.outer(v, v) + kf.P[p:, p:])
        nu = y - (kf.H @ kf.x)[:, 0]
        S = kf.H @ kf.P @ kf.H.T + R
        self.last_d2 = float(nu @ np.linalg.solve(S, nu))
        if self.last_d2 <= self._gate:
            kf.update(y, R=R)
            self._rejects = 0
            self.status = ACCEPTED
        elif self._rejects + 1 >= self.config.max_rejects:
            self._initialise(y)
            self.status = RESET
        else:
            self._rejects += 1
            self.status = REJECTED


@dataclass(frozen=True)
class FilterRun:
    """What :func:`filter_track` computed for every sample k.

    Attributes
    ----------
    times : ndarray, shape (T,)
        Sample times (s), non-decreasing.
    filtered : ndarray, shape (T, P)
        Causal position estimate after sample k (m); NaN before the first sample.
    status : ndarray of int, shape (T,)
        Status code of each sample (:data:`STATUS_NAMES`).
    means, covs : ndarray, shapes (T, 2P) and (T, 2P, 2P)
        Posterior state after sample k (meaningful from the first accepted one).
    Fs, Qs : ndarray, shapes (T, 2P, 2P)
        Transition and process noise from sample k-1 to sample k.
    """

    times: FloatArray
    filtered: FloatArray
    status: np.ndarray
    means: FloatArray
    covs: FloatArray
    Fs: FloatArray
    Qs: FloatArray

    @property
    def used(self) -> np.ndarray:
        """Boolean mask, shape (T,): samples the filter used (accepted, init or reset)."""
        return np.isin(self.status, (ACCEPTED, INIT, RESET))

    def counts(self) -> dict[str, int]:
        """Number of samples per status name."""
        return {name: int(np.sum(self.status == i)) for i, name in enumerate(STATUS_NAMES)}


def filter_track(
    times: ArrayLike, values: ArrayLike, config: FilterConfig | None = None
) -> FilterRun:
    """Run the causal filter of :class:`HandFilter` over a whole track.

    The same model and arithmetic as feeding :class:`HandFilter` sample by
    sample (:func:`filter_track_reference`, which the tests hold it to, 1e-9),
    computed on plain arrays (:mod:`sandbox.data.kalman`), about ten times faster.

    Parameters
    ----------
    times : array_like, shape (T,)
        Sample times (s), non-decreasing (equal times allowed).
    values : array_like, shape (T, P)
        Positions (m); NaN marks a missing sample.
    config : FilterConfig, optional
        Filter settings.

    Returns
    -------
    FilterRun
    """
    t, y, config = _check_track(times, values, config)
    skip = kalman.classify(y)
    out = kalman.forward(t, y, config, config.gate(y.shape[1]), skip)
    return FilterRun(t, **out)


def filter_track_reference(
    times: ArrayLike, values: ArrayLike, config: FilterConfig | None = None
) -> FilterRun:
    """:func:`filter_track` computed by feeding :class:`HandFilter` (filterpy) sample by sample."""
    t, y, config = _check_track(times, values, config)
    f = HandFilter(y.shape[1], config)
    d = 2 * y.shape[1]
    out = np.full(y.shape, np.nan)
    status = np.zeros(t.size, dtype=int)
    means, covs = np.zeros((t.size, d)), np.zeros((t.size, d, d))
    Fs, Qs = np.tile(np.eye(d), (t.size, 1, 1)), np.zeros((t.size, d, d))
    for k in range(t.size):
        out[k] = f.update(t[k], y[k])
        status[k] = f.status
        if f.initialised:
            means[k], covs[k] = f.state
        if status[k] not in (WAITING, INIT):
            Fs[k], Qs[k] = f.last_F, f.last_Q
    return FilterRun(t, out, status, means, covs, Fs, Qs)


def _check_track(times, values, config):
    t = check_array(times, "times", 1, min_len=1)
    y = check_array(values, "values", 2, shape=(t.size, None), allow_nan=True)
    if np.any(np.diff(t) < 0):
        raise ValueError("times: expected non-decreasing times, got a decrease")
    if config is not None and not isinstance(config, FilterConfig):
        raise ValueError(f"config: expected a FilterConfig, got {type(config).__name__}")
    return t, y, config if config is not None else FilterConfig()


def smooth_track(run: FilterRun, config: FilterConfig | None = None) -> FloatArray:
    """Rauch-Tung-Striebel smoothed positions (m), shape (T, P), from a :class:`FilterRun`.

    Samples before the first accepted one stay NaN (nothing to smooth from).
    A filter reset starts a new segment: the smoother does not blend across it.
    Computed by :func:`sandbox.data.kalman.rts_means`; :func:`smooth_track_reference`
    (filterpy's smoother) gives the same to 1e-9.
    """
    return _smooth(run, kalman.rts_means)


def smooth_track_reference(run: FilterRun, config: FilterConfig | None = None) -> FloatArray:
    """:func:`smooth_track` computed by :meth:`filterpy.kalman.KalmanFilter.rts_smoother`."""
    from filterpy.kalman import KalmanFilter
    kf = KalmanFilter(dim_x=run.means.shape[1], dim_z=run.filtered.shape[1])

    def means(xs, ps, fs, qs):
        return kf.rts_smoother(xs.copy(), ps.copy(), Fs=fs, Qs=qs, inv=np.linalg.pinv)[0]

    return _smooth(run, means)


def _smooth(run: FilterRun, smoother) -> FloatArray:
    n = run.filtered.shape[1]
    out = np.full(run.filtered.shape, np.nan)
    starts = np.flatnonzero(np.isin(run.status, (INIT, RESET)))
    ends = np.r_[starts[1:], run.status.size].astype(int) if starts.size else starts
    for a, b in zip(starts, ends, strict=True):
        xs = smoother(run.means[a:b], run.covs[a:b], run.Fs[a:b], run.Qs[a:b])
        out[a:b] = xs[:, :n]
    return out
