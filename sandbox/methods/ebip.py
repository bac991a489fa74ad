"""Ensemble BIP (Campbell, Stepputtis & Ben Amor 2019): an ensemble Kalman filter, no Jacobian.

Task k keeps an ensemble of E members :math:`x_j = [\\phi_j, \\dot\\phi_j, \\omega_j]`
seeded with its demonstrations: :math:`\\omega_j` a demo's weights (eq. 6,
human dims normalised), :math:`\\dot\\phi_j = 1/T_j` its own phase velocity,
:math:`\\phi_j \\sim \\mathcal{N}(0, \\sigma_{\\phi_0}^2)`. With ``ensemble_size``
larger than the demos, the extra members are drawn from the core's
:math:`\\mathcal{N}(\\mu_\\omega, \\Sigma_\\omega)` and the velocity prior.
Each kept observation is one step (Evensen 2003, perturbed observations):

.. math::
    \\phi_j \\leftarrow \\phi_j + \\dot\\phi_j \\Delta t + \\epsilon_j, \\quad
    \\epsilon_j \\sim \\mathcal{N}(0, Q(\\Delta t))

.. math::
    h_j = \\Psi(\\phi_j)^T \\omega_{j,obs}, \\quad
    S = \\tfrac{1}{E-1} (HA)(HA)^T + \\Sigma_y, \\quad
    K = \\tfrac{1}{E-1} A (HA)^T S^{-1}, \\quad
    x_j \\leftarrow x_j + K (y + \\eta_j - h_j)

with :math:`A` and :math:`HA` the deviations of the members and of their
projections from their means, :math:`\\eta_j \\sim \\mathcal{N}(0, \\Sigma_y)`,
:math:`Q` the piecewise white-noise model of :mod:`sandbox.methods.bip` and the
phases clipped to [0, 1]. The robot prediction is the members' robot weights
(mean, and sample covariance plus the core's robot regulariser :math:`\\Lambda_r`,
so it stays positive definite with E below Q·N) at the mean phase and velocity.

**Recognition**: one ensemble per task; the log-likelihood of task k sums
:math:`\\log\\mathcal{N}(y_t; \\bar h_t, S_t)` over the steps (the ensemble's
predictive density), normalised over tasks with p(k) (eq. 14-15).

Choices where the paper and intprim leave it open: intprim draws every
member's initial phase and velocity from one Gaussian; here each demo keeps
its own velocity (the ensemble is the demonstrations, timing included). The
noise settings are BIP's (``phase_std``, ``process_noise``). Random numbers
come from a generator seeded with ``seed`` at every :meth:`reset`, so a
predictor fed the same stream makes the same predictions.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
from numpy.typing import NDArray

from sandbox.methods.base import MIN_RATE, MethodPredictor, end_time, robot_from_members
from sandbox.methods.bip import rate_prior
from sandbox.validation import FloatArray, check_integer, check_positive


class EnsembleFilter:
    """The ensemble Kalman filter of one task (module docstring).

    Parameters
    ----------
    members : ndarray, shape (E, 2 + D*N)
        Initial ensemble: phase, phase velocity (1/s), weights.
    n_basis : int
    noise : ndarray, shape (P,)
        Observation noise variances of the human dims.
    process_noise : float
        q of the phase system (1/s^4).
    basis : GaussianBasis
    rng : numpy.random.Generator
    """

    def __init__(self, members: FloatArray, n_basis: int, noise, process_noise: float,
                 basis, rng: np.random.Generator) -> None:
        self.X = np.array(members, dtype=float)
        self.N, self.noise, self.q = int(n_basis), np.asarray(noise), process_noise
        self.basis, self.rng = basis, rng
        self.time = 0.0
        self.log_likelihood = 0.0

    @property
    def size(self) -> int:
        """E."""
        return self.X.shape[0]

    def predict(self, t: float) -> None:
        """Advance every member's phase to time ``t`` (s), with process noise."""
        dt = max(t - self.time, 0.0)
        self.time = max(t, self.time)
        if dt == 0.0:
            return
        self.X[:, 0] += self.X[:, 1] * dt
        if self.q > 0:
            Q = self.q * np.array([[dt**4 / 4, dt**3 / 2], [dt**3 / 2, dt**2]])
            self.X[:, :2] += self.rng.multivariate_normal(np.zeros(2), Q, size=self.size,
                                                          method="eigh")
        self._clip()

    def project(self, obs: NDArray[np.intp]) -> FloatArray:
        """:math:`h_j`: every member's observed dims ``obs`` at its phase, shape (E, m)."""
        psi = self.basis.evaluate(np.clip(self.X[:, 0], 0.0, 1.0))          # (E, N)
        W = self.X[:, 2:].reshape(self.size, -1, self.N)[:, obs, :]         # (E, m, N)
        return np.einsum("en,emn->em", psi, W)

    def correct(self, y: FloatArray) -> None:
        """Update on one observation ``y`` (P,), NaN where unobserved."""
        obs = np.flatnonzero(np.isfinite(y))
        if obs.size == 0:
            return
        E = self.size
        hx = self.project(obs)
        A = self.X - self.X.mean(axis=0)
        HA = hx - hx.mean(axis=0)
        R = self.noise[obs]
        S = HA.T @ HA / (E - 1) + np.diag(R)
        L = scipy.linalg.cho_factor(S, lower=True)
        nu = y[obs] - hx.mean(axis=0)
        logdet = 2.0 * np.log(np.diag(L[0])).sum()
        self.log_likelihood += -0.5 * (nu @ scipy.linalg.cho_solve(L, nu) + logdet
                                       + obs.size * np.log(2 * np.pi))
        perturbed = y[obs] + self.rng.standard_normal((E, obs.size)) * np.sqrt(R)
        gain_t = scipy.linalg.cho_solve(L, HA.T @ A / (E - 1))               # K^T, (m, n)
        self.X += (perturbed - hx) @ gain_t
        self._clip()

    def _clip(self) -> None:
        np.clip(self.X[:, 0], 0.0, 1.0, out=self.X[:, 0])
        np.maximum(self.X[:, 1], MIN_RATE, out=self.X[:, 1])


def initial_ensemble(weights: FloatArray, durations: FloatArray, mean: FloatArray,
                     cov_factor: FloatArray, reg_diag: FloatArray, size: int,
                     phase_std: float, rng: np.random.Generator) -> FloatArray:
    """The demos (weights, own velocity 1/T_i, phase ~ N(0, phase_std^2)), plus members drawn
    from N(mean, U U^T + diag(reg_diag)) and the velocity prior up to ``size``; shape (E, 2+D*N),
    E = max(size, n_demos)."""
    n = weights.shape[0]
    rates = 1.0 / np.asarray(durations, dtype=float)
    extra = max(size - n, 0)
    if extra:
        r_mean, r_std = rate_prior(durations)
        z = rng.standard_normal((extra, cov_factor.shape[1]))
        drawn = mean + z @ cov_factor.T + rng.standard_normal((extra, mean.size)) \
            * np.sqrt(reg_diag)
        weights = np.vstack([weights, drawn])
        rates = np.r_[rates, np.maximum(r_mean + r_std * rng.standard_normal(extra), MIN_RATE)]
    phases = phase_std * rng.standard_normal(rates.size)
    return np.c_[np.clip(phases, 0.0, 1.0), rates, weights]


class EBIPPredictor(MethodPredictor):
    """eBIP behind the predictor interface: one :class:`EnsembleFilter` per task.

    Parameters
    ----------
    library : DemoLibrary
    dow_t : float
        Seconds between updates (the filter runs on every kept observation).
    ensemble_size : int
        Members per task; 0 (default) keeps exactly the demos, more adds members
        drawn from the weight distribution (module docstring).
    phase_std, process_noise : float
        As for :class:`~sandbox.methods.bip.BIPPredictor`.
    seed : int
        Seed of the filter's random numbers (perturbations, process noise).
    **options
        Of :class:`~sandbox.methods.base.MethodPredictor`.
    """

    name = "ebip"

    def __init__(self, library, dow_t: float = 0.2, *, ensemble_size: int = 0,
                 phase_std: float = 0.02, process_noise: float = 1.0, seed: int = 0,
                 **options) -> None:
        self.ensemble_size = check_integer(ensemble_size, "ensemble_size", 0, 100_000)
        self.phase_std = check_positive(phase_std, "phase_std", allow_zero=True)
        self.process_noise = check_positive(process_noise, "process_noise", allow_zero=True)
        self.seed = check_integer(seed, "seed", 0)
        super().__init__(library, dow_t, **options)

    def _reset_method(self) -> None:
        model, lib = self.library.model, self.library
        rng = np.random.default_rng(self.seed)
        self.filters = []
        for k, task in enumerate(model.task_models):
            w = task.weights
            members = initial_ensemble(lib.weights[k], lib.durations[k], w.mean, w.factor,
                                       w.reg_diag, self.ensemble_size, self.phase_std, rng)
            rate = rate_prior(lib.durations[k])[0]
            self.filters.append(EnsembleFilter(members, model.basis.n_basis, model.noise,
                                               self.process_noise * rate**4, model.basis, rng))

    def estimate(self, t, times, values):
        self._feed_filters(t, times, values)
        model = self.library.model
        N, PN = model.basis.n_basis, model.n_human * model.basis.n_basis

        def robot(k: int):
            X, reg = self.filters[k].X, model.task_models[k].weights.reg[model.n_human:]
            return robot_from_members(X[:, 2 + PN:].mean(axis=0), X[:, 2 + PN:], reg, N)

        means = [f.X[:, :2].mean(axis=0) for f in self.filters]
        durations = [end_time(m[0], m[1], t) for m in means]
        ll = np.array([f.log_likelihood for f in self.filters])
        return self._make_prediction(ll, durations, robot, [m[0] for m in means],
                                     [m[1] for m in means], t)
