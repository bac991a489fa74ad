"""Open-end dynamic time warping against every training demo, and its robot part.

The observed prefix :math:`y_{1:s}` (kept observations, observed dims) is
aligned with each training demo's human trajectory :math:`r_{i}(z_j)`, its
basis reconstruction at M phases :math:`z_j = j/(M-1)`, by the accumulated cost

.. math::
    D[a, j] = c(a, j) + \\min_{0 \\le m \\le 3} D[a-1, j-m], \\qquad
    c(a, j) = \\sum_{d\\,\\mathrm{observed}} (y_{a,d} - r_{i,d}(z_j))^2 / \\sigma_{y,d}^2

(both start at their beginning; the end is open: the prefix may end anywhere
in the demo). The distance of demo i is :math:`d_i = \\min_j D[s, j]` and the
phase it reached :math:`z^*_i = z_{j^*}`. Costs are normalised by the core's
observation noise, so positions (m) and signals weigh by their noise.

**Prediction**: the robot part of the best demo, or with ``k > 1`` the
average of the k best demos' robot weights weighted by :math:`1/\\bar d_i`
(:math:`\\bar d_i = d_i / s`, the cost per observation), their weighted
spread plus the core's robot regulariser as covariance. It is time-warped to
the remaining duration: the human reached phase :math:`z^*` in the time
``t`` observed, so the motion lasts :math:`\\hat T = t / z^*` (the weighted
mean of the k best), clipped to [0.5, 2] x the task's demo durations' range;
the robot's phase is :math:`\\tau/\\hat T`.

**Recognition**: the best distance of each task,
:math:`\\log p(y | k) = -\\tfrac12 \\min_{i \\in k} d_i` (the cost is
:math:`-2\\log` of the Gaussian observation noise along the path), normalised
over tasks with p(k) (eq. 14-15).

Choices left open: M = ``n_samples`` (default 50, 2 % of the phase); the
asymmetric step pattern above (every observation adds exactly one cost term,
so distances of paths ending anywhere compare; the reference advances at most
:data:`MAX_STEP` samples per observation: a motion observed at 15 Hz may be 3x
faster than the demo on 50 samples). The symmetric pattern (steps (1,0),
(0,1), (1,1)) adds a cost for every reference sample passed, which biased
the reached phase low and the duration high on the recorded handovers
(e_phi 1.25 s, hand, leave-one-out). The alignment is extended incrementally,
one row per kept observation (exactly the batch result).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sandbox.methods.base import MethodPredictor, robot_from_members
from sandbox.validation import FloatArray, check_integer

#: Most reference samples the alignment advances per observation.
MAX_STEP = 3
#: Ratio bounds of the time-warped duration to the task's demo durations.
WARP_BOUNDS = (0.5, 2.0)


def dtw_rows(cost: FloatArray, previous: FloatArray | None,
             max_step: int = MAX_STEP) -> FloatArray:
    """The next rows of the accumulated cost, shape (n, M), from this observation's
    ``cost`` (n, M) against n references and the previous rows (None for the first)."""
    if previous is None:
        out = np.full_like(cost, np.inf)
        out[:, 0] = cost[:, 0]                          # both start at their beginning
        return out
    best = previous.copy()
    for step in range(1, max_step + 1):                 # the reference advances 0..max_step
        np.minimum(best[:, step:], previous[:, :-step], out=best[:, step:])
    return best + cost


def dtw_distance(query: FloatArray, reference: FloatArray, noise: FloatArray) -> tuple[float, int]:
    """Open-end DTW of ``query`` (s, P) against ``reference`` (M, P): distance and end index."""
    rows = None
    for y in query:
        ok = np.isfinite(y)
        c = (((reference[:, ok] - y[ok]) ** 2) / noise[ok]).sum(axis=1)[None]
        rows = dtw_rows(c, rows)
    if rows is None:
        raise ValueError("query: expected at least one observation, got none")
    return float(rows[0].min()), int(np.argmin(rows[0]))


class DTWPredictor(MethodPredictor):
    """Open-end DTW nearest demos behind the predictor interface (module docstring).

    Parameters
    ----------
    library : DemoLibrary
    dow_t : float
        Seconds between updates.
    k : int
        Demos averaged (1: the best match).
    n_samples : int
        Samples M of each demo's phase.
    **options
        Of :class:`~sandbox.methods.base.MethodPredictor`.
    """

    name = "dtw"

    def __init__(self, library, dow_t: float = 0.2, *, k: int = 1, n_samples: int = 50,
                 **options) -> None:
        self.k = check_integer(k, "k", 1)
        self.n_samples = check_integer(n_samples, "n_samples", 2, 10_000)
        super().__init__(library, dow_t, **options)
        z = np.linspace(0.0, 1.0, self.n_samples)
        self._refs = [library.human(i, z) for i in range(len(library.weights))]   # (n_k, M, P)

    def _reset_method(self) -> None:
        self._rows: list[FloatArray | None] = [None] * len(self.library.weights)

    def estimate(self, t, times, values):
        noise = self.library.model.noise
        for y in values[self._fed:]:
            ok = np.isfinite(y)
            if not ok.any():
                continue
            for i, ref in enumerate(self._refs):
                c = (((ref[:, :, ok] - y[ok]) ** 2) / noise[ok]).sum(axis=2)
                self._rows[i] = dtw_rows(c, self._rows[i])
        self._fed = times.size
        z = np.linspace(0.0, 1.0, self.n_samples)
        t_last = float(times[-1])
        ll, durations, picks = [], [], []
        for k, rows in enumerate(self._rows):
            assert rows is not None             # an update follows a valid observation
            d, j = rows.min(axis=1), rows.argmin(axis=1)
            order = np.argsort(d)[:self.k]
            w = 1.0 / np.maximum(d[order] / times.size, 1e-12)
            w /= w.sum()
            T_k = self.library.durations[k]
            lo, hi = WARP_BOUNDS[0] * T_k.min(), WARP_BOUNDS[1] * T_k.max()
            warped = np.clip(t_last / np.maximum(z[j[order]], 1e-9), lo, hi)
            ll.append(-0.5 * d[order[0]])
            durations.append(max(float(w @ warped), t_last if z[j[order[0]]] >= 1 else 0.0))
            picks.append((order, w))
        return self._make_prediction(np.array(ll), durations,
                                     lambda k: _weighted_robot(self.library, k, *picks[k]))


def _weighted_robot(library, k: int, order: NDArray[np.intp], w: FloatArray):
    """Robot distribution of task k's demos ``order`` weighted by ``w`` (sum 1)."""
    model = library.model
    robots = library.robot_weights(k)[order]
    mean = w @ robots
    reg = model.task_models[k].weights.reg[model.n_human:]
    if order.size == 1:
        return robot_from_members(mean, robots, reg, model.basis.n_basis)
    members = mean + (robots - mean) * np.sqrt(w * (order.size - 1))[:, None]
    return robot_from_members(mean, members, reg, model.basis.n_basis)
