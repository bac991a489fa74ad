"""Nearest neighbour: the training demo closest to the phase-normalised observed prefix.

Each training demo i of duration :math:`T_i` is compared with the prefix at
its own timing: observation :math:`y_a` at time :math:`t_a` against the demo's
basis reconstruction at phase :math:`z = \\min(t_a / T_i, 1)`,

.. math::
    d_i = \\sum_a \\sum_{d\\,\\mathrm{observed}} (y_{a,d} - r_{i,d}(t_a / T_i))^2 / \\sigma_{y,d}^2

(no warping: that is :mod:`sandbox.methods.dtw`). The prediction is the
nearest demo's robot weights at its own duration :math:`T_i`, with the core's
robot regulariser :math:`\\Lambda_r` as covariance (one demo has no spread).

**Recognition**: :math:`\\log p(y | k) = -\\tfrac12 \\min_{i \\in k} d_i` (the
cost is :math:`-2\\log` of the Gaussian observation noise), normalised over
tasks with p(k) (eq. 14-15).
"""

from __future__ import annotations

import numpy as np

from sandbox.methods.base import MethodPredictor, robot_from_members
from sandbox.validation import FloatArray


def distances(library, k: int, times: FloatArray, values: FloatArray) -> FloatArray:
    """:math:`d_i` of every demo of task ``k`` for observations ``values`` (s, P) at
    ``times`` (s,), NaN where unobserved; shape (n_k,)."""
    model = library.model
    z = np.minimum(times[None, :] / library.durations[k][:, None], 1.0)       # (n_k, s)
    psi = model.basis.evaluate(z)                                               # (n_k, s, N)
    P, N = model.n_human, model.basis.n_basis
    W = library.weights[k][:, :P * N].reshape(-1, P, N)
    ref = np.einsum("isn,ipn->isp", psi, W)
    err = (values[None] - ref) ** 2 / model.noise
    return np.where(np.isfinite(err), err, 0.0).sum(axis=(1, 2))


class NearestPredictor(MethodPredictor):
    """Nearest training demo behind the predictor interface (module docstring).

    Parameters
    ----------
    library : DemoLibrary
    dow_t : float
        Seconds between updates.
    **options
        Of :class:`~sandbox.methods.base.MethodPredictor`.
    """

    name = "nearest"

    def estimate(self, t, times, values):
        lib, model = self.library, self.library.model
        ll, durations, best = [], [], []
        for k in range(len(lib.weights)):
            d = distances(lib, k, times, values)
            i = int(np.argmin(d))
            ll.append(-0.5 * d[i])
            durations.append(float(lib.durations[k][i]))
            best.append(i)

        def robot(k: int):
            members = lib.robot_weights(k)[best[k]:best[k] + 1]
            reg = model.task_models[k].weights.reg[model.n_human:]
            return robot_from_members(members[0], members, reg, model.basis.n_basis)

        return self._make_prediction(np.array(ll), durations, robot)
