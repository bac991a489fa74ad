"""Array implementation of the gated hand filter and its RTS smoother.

:class:`sandbox.data.filtering.HandFilter` (built on :mod:`filterpy`) is the
reference: it takes one sample at a time, as a live tracker gives them. This
module runs the same model over a whole recorded track at once, with the
same arithmetic on plain arrays (no per-sample object, copies or checks) and
a smoother whose gains are computed for all samples in one batch:

* forward pass (:func:`forward`): the constant-velocity prediction
  ``x = F x``, ``P = F P F^T + Q`` and, for a sample the gate accepts, the
  Kalman update in Joseph form, ``P = (I - K H) P (I - K H)^T + K R K^T``, as
  :meth:`filterpy.kalman.KalmanFilter.update` computes it;
* smoother (:func:`rts_means`): Rauch-Tung-Striebel,
  ``x_s[k] = x[k] + K_k (x_s[k+1] - F_{k+1} x[k])`` with
  ``K_k = P[k] F_{k+1}^T (F_{k+1} P[k] F_{k+1}^T + Q_{k+1})^+``.

``tests/data/test_kalman.py`` checks both against filterpy to 1e-9 on every
recorded track and on synthetic tracks with dropouts, repeats and jumps.
"""

from __future__ import annotations

from collections import deque
from typing import Any

import numpy as np

from sandbox.validation import FloatArray

# Status codes: the same as sandbox.data.filtering's (kept in step by its tests).
WAITING, MISSING, ACCEPTED, REJECTED, INIT, RESET, STALE = range(7)


def classify(values: FloatArray, *, zero_is_missing: bool = True, drop_repeats: bool = True,
             repeat_window: int = 64) -> np.ndarray:
    """Per-sample MISSING / STALE / -1 (a new sample), shape (T,).

    A sample with a NaN, or all zeros, is missing; one equal to any of the last
    ``repeat_window`` distinct new samples is stale (the tracker re-sent it).
    This depends only on the samples, not on the filter's state.
    """
    out = np.full(values.shape[0], -1)
    missing = np.isnan(values).any(axis=1)
    if zero_is_missing:
        missing |= (values == 0.0).all(axis=1)
    out[missing] = MISSING
    if drop_repeats:
        recent: deque[bytes] = deque(maxlen=int(repeat_window))
        for k in np.flatnonzero(~missing):
            key = values[k].tobytes()
            if key in recent:
                out[k] = STALE
            else:
                recent.append(key)
    return out


def forward(times: FloatArray, values: FloatArray, config: Any, gate: float,
            skip: np.ndarray) -> dict[str, np.ndarray]:
    # Over 60 lines: the fast filter's hot loop over samples, kept whole (no calls per step).
    """The gated filter over a track (see :func:`sandbox.data.filtering.filter_track`).

    Parameters
    ----------
    times : ndarray, shape (T,)
        Non-decreasing sample times (s).
    values : ndarray, shape (T, P)
        Positions (m).
    config : FilterConfig
    gate : float
        Threshold on the squared Mahalanobis distance.
    skip : ndarray of int, shape (T,)
        :func:`classify`'s codes.

    Returns
    -------
    dict
        ``filtered`` (T, P), ``status`` (T,), ``means`` (T, 2P), ``covs``
        (T, 2P, 2P), ``Fs`` and ``Qs`` (T, 2P, 2P), as in
        :class:`~sandbox.data.filtering.FilterRun`.
    """
    T, p = values.shape
    d = 2 * p
    eye_p, eye_d = np.eye(p), np.eye(d)
    H = np.hstack([eye_p, np.zeros((p, p))])
    R0 = config.noise_std**2 * eye_p
    jit2 = config.time_jitter_std**2
    q = config.accel_std**2
    # Q(dt) = q * kron([[dt^3/3, dt^2/2], [dt^2/2, dt]], I) (white acceleration, per axis)
    q_pp, q_pv, q_vv = (np.kron(np.array(b, float), eye_p) for b in
                        ([[1, 0], [0, 0]], [[0, 1], [1, 0]], [[0, 0], [0, 1]]))
    p0 = np.diag(np.r_[np.full(p, config.noise_std**2), np.full(p, config.init_speed_std**2)])
    filtered = np.full((T, p), np.nan)
    status = np.zeros(T, dtype=int)
    means, covs = np.zeros((T, d)), np.zeros((T, d, d))
    Fs, Qs = np.tile(eye_d, (T, 1, 1)), np.zeros((T, d, d))
    x, P = np.zeros(d), p0
    started, rejects, last_t = False, 0, 0.0
    for k in range(T):
        t, y, code = times[k], values[k], skip[k]
        if not started:
            last_t = t
            if code < 0:
                x, P, started, rejects = np.r_[y, np.zeros(p)], p0.copy(), True, 0
                status[k] = INIT
            else:
                status[k] = WAITING
                continue
        else:
            dt = t - last_t
            last_t = t
            F = eye_d.copy()
            F[:p, p:] = dt * eye_p
            Q = q * (dt**3 / 3 * q_pp + dt**2 / 2 * q_pv + dt * q_vv)
            Fs[k], Qs[k] = F, Q
            if dt > 0:
                x = F @ x
                P = F @ P @ F.T + Q
            if code >= 0:
                status[k] = code
            else:
                v = x[p:]
                R = R0 + jit2 * (np.outer(v, v) + P[p:, p:])
                nu = y - x[:p]
                S = P[:p, :p] + R
                d2 = nu @ np.linalg.solve(S, nu)
                if d2 <= gate:
                    PHT = P[:, :p]
                    K = PHT @ np.linalg.inv(PHT[:p] + R)
                    x = x + K @ nu
                    I_KH = eye_d - K @ H
                    P = I_KH @ P @ I_KH.T + K @ R @ K.T
                    rejects, status[k] = 0, ACCEPTED
                elif rejects + 1 >= config.max_rejects:
                    x, P, rejects = np.r_[y, np.zeros(p)], p0.copy(), 0
                    status[k] = RESET
                else:
                    rejects, status[k] = rejects + 1, REJECTED
        filtered[k], means[k], covs[k] = x[:p], x, P
    return {"filtered": filtered, "status": status, "means": means, "covs": covs,
            "Fs": Fs, "Qs": Qs}


def rts_means(means: FloatArray, covs: FloatArray, Fs: FloatArray, Qs: FloatArray) -> FloatArray:
    """Rauch-Tung-Striebel smoothed state means, shape (T, 2P), of one filter segment.

    ``Fs[k]``, ``Qs[k]`` take the state from sample k-1 to sample k (``Fs[0]``
    is unused). The gains of all samples are computed in one batch; only the
    backward recursion of the means runs sample by sample. Uses the
    pseudo-inverse, as the loader's call of filterpy's smoother does.
    """
    x = means.copy()
    if x.shape[0] < 2:
        return x
    F1, Q1, P = Fs[1:], Qs[1:], covs[:-1]
    Pp = F1 @ P @ np.swapaxes(F1, 1, 2) + Q1
    K = P @ np.swapaxes(F1, 1, 2) @ np.linalg.pinv(Pp)
    prior = np.einsum("kij,kj->ki", F1, means[:-1])
    for k in range(x.shape[0] - 2, -1, -1):
        x[k] += K[k] @ (x[k + 1] - prior[k])
    return x
