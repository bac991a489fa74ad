"""The training demonstrations the other methods keep, as the IProMP core fits them.

BIP's prior is the core's weight distribution; eBIP, DTW and nearest-neighbour
need the demonstrations themselves. A :class:`DemoLibrary` holds, per task, each
training demo's weights (the core's ridge fit, eq. 2, human dims normalised as
the model normalises them) and its motion duration (s). A demo's trajectory is
its basis reconstruction :math:`\\Psi(z) \\omega_i` (eq. 1): the same smoothing
and the same cut at the motion's end (:func:`~sandbox.core.fitting.motion_end`)
every method sees, so the methods differ only in how they estimate.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from sandbox.validation import FloatArray

if TYPE_CHECKING:
    from sandbox.core.fitting import DemoFit
    from sandbox.core.model import IProMP


@dataclass(frozen=True, eq=False)
class DemoLibrary:
    """Each task's demo weights and durations, in the model's task order.

    Attributes
    ----------
    model : IProMP
        The model fitted on the same demos (basis, noise, scale, tasks, priors).
    weights : tuple of ndarray, each shape (n_k, (P+Q)*N)
        Demo weights of task k, human dims in normalised units (eq. 6 layout).
    durations : tuple of ndarray, each shape (n_k,)
        Motion durations (s).
    exact : bool
        True when the weights are the demos'; False for :meth:`from_model`'s
        moment-matched stand-ins.
    """

    model: IProMP
    weights: tuple[FloatArray, ...]
    durations: tuple[FloatArray, ...]
    exact: bool = True

    @classmethod
    def from_fits(cls, model: IProMP, fits: Sequence[DemoFit]) -> DemoLibrary:
        """From the per-demo fits the model was fitted on (:meth:`IProMP.demo_fit`)."""
        N = model.basis.n_basis
        divide = np.r_[model.scale, np.ones(model.n_robot)].repeat(N)
        weights, durations = [], []
        for task in model.tasks:
            mine = [f for f in fits if f.task == task]
            if len(mine) < 2:
                raise ValueError(f"fits: expected at least two demos of task {task!r}, "
                                 f"got {len(mine)}")
            weights.append(np.array([f.weights for f in mine]) / divide)
            durations.append(np.array([f.duration for f in mine]))
        return cls(model, tuple(weights), tuple(durations))

    @classmethod
    def from_demos(cls, model: IProMP, demos) -> DemoLibrary:
        """From demonstrations (each fitted as :meth:`IProMP.demo_fit` fits it)."""
        return cls.from_fits(model, [model.demo_fit(d) for d in demos])

    @classmethod
    def from_model(cls, model: IProMP) -> DemoLibrary:
        """Stand-ins for the demos when only a model is at hand (e.g. a model file).

        Each task gets ``n_demos`` members :math:`\\mu + \\sqrt{n-1}\\,U R` with
        ``R`` orthonormal rows orthogonal to the ones vector: their mean and
        sample covariance are exactly the model's :math:`\\mu_\\omega, UU^T`,
        and their durations spread :math:`T_{nom}(1 \\pm \\sigma_\\alpha)` with
        the same moments. Deterministic (no random numbers).
        """
        weights, durations = [], []
        for task in model.task_models:
            n = max(int(task.n_demos), task.weights.factor.shape[1] + 1, 2)
            R = _zero_sum_rows(task.weights.factor.shape[1], n)
            weights.append(task.weights.mean + np.sqrt(n - 1) * (task.weights.factor @ R).T)
            spread = _zero_sum_rows(1, n)[0] * np.sqrt(n - 1)
            durations.append(task.nominal_duration * (task.alpha_mean + task.alpha_std * spread))
        return cls(model, tuple(weights), tuple(durations), exact=False)

    def human(self, k: int, z: FloatArray) -> FloatArray:
        """Every demo of task ``k``'s human dims at phases ``z`` (T,): shape (n_k, T, P)."""
        P, N = self.model.n_human, self.model.basis.n_basis
        psi = self.model.basis.evaluate(np.clip(np.asarray(z, dtype=float), 0.0, 1.0))
        w = self.weights[k][:, :P * N].reshape(-1, P, N)
        return np.einsum("tn,ipn->itp", psi, w)

    def robot_weights(self, k: int) -> FloatArray:
        """Task ``k``'s demo robot weights, shape (n_k, Q*N)."""
        return self.weights[k][:, self.model.n_human * self.model.basis.n_basis:]


def _zero_sum_rows(r: int, n: int) -> FloatArray:
    """``r`` orthonormal rows of length ``n`` (r < n), each orthogonal to the ones vector."""
    basis = np.linalg.qr(np.c_[np.ones(n), np.eye(n)[:, :n - 1]])[0]
    return basis[:, 1:r + 1].T
