"""Bayesian Interaction Primitives (Campbell & Ben Amor 2017): an EKF over phase and weights.

The state of task k is :math:`s = [\\phi, \\dot\\phi, \\omega]`: the phase, the
phase velocity (1/s) and the weights of all P human + Q robot dims (eq. 6
layout, the IProMP core's basis). The prior is
:math:`\\phi \\sim \\mathcal{N}(0, \\sigma_{\\phi_0}^2)`,
:math:`\\dot\\phi \\sim \\mathcal{N}(\\overline{1/T_i}, \\mathrm{var}(1/T_i))`
over the task's demos, and :math:`\\omega \\sim \\mathcal{N}(\\mu_\\omega, \\Sigma_\\omega)`
the core's weight distribution (regulariser included). Each observation
:math:`y_t` (the observed human dims) is one EKF step:

.. math::
    \\text{predict: } \\phi \\leftarrow \\phi + \\dot\\phi\\,\\Delta t, \\quad
    P \\leftarrow F P F^T + q \\begin{bmatrix}\\Delta t^4/4 & \\Delta t^3/2 \\\\
    \\Delta t^3/2 & \\Delta t^2\\end{bmatrix}

.. math::
    h(s) = \\Psi(\\phi)^T \\omega_{obs}, \\quad
    H = [\\Psi'(\\phi)^T\\omega_{obs},\\ 0,\\ \\Psi(\\phi)^T], \\quad
    S = H P H^T + \\Sigma_y, \\quad K = P H^T S^{-1}

with the phase clipped to [0, 1] (a motion holds its end, as in the core) and
:math:`\\Sigma_y` the core's observation noise (the same for every method).

**Recognition**: one filter per task; the log-likelihood of task k is the sum
of its innovations' :math:`\\log\\mathcal{N}(\\nu_t; 0, S_t)` (the prediction-error
decomposition of :math:`p(y_{1:t} | k)`), normalised over tasks with the
priors p(k) (eq. 14-15).

Choices where the paper and intprim leave it open (intprim counts time in
samples with :math:`\\Delta t = 1`; here time is in seconds):

* the filter runs on the kept observations (1 in ``subsample``) with their
  real time steps, and its robot prediction is read every ``dow_t``;
* the process noise is intprim's piecewise white-noise model on the phase
  acceleration, with :math:`q` = ``process_noise`` x :math:`\\overline{1/T_i}^2`
  (1/s^4): scale-free across tasks of different durations;
* :math:`\\sigma_{\\phi_0}` = ``phase_std`` (default 0.02: the recordings start
  with the motion);
* :math:`\\Psi'` is the basis' derivative by central differences;
* the phase velocity stays >= :data:`~sandbox.methods.base.MIN_RATE`.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from sandbox.methods.base import MIN_RATE, MethodPredictor, end_time, robot_from_cov
from sandbox.validation import FloatArray, check_positive

#: Step of the central difference of the basis' derivative (phase units).
DERIVATIVE_STEP = 1e-6


def basis_and_derivative(basis, z: float) -> tuple[FloatArray, FloatArray]:
    """:math:`\\psi(z)` and :math:`\\psi'(z)`, each shape (N,); zero derivative outside [0, 1]."""
    zc = min(max(z, 0.0), 1.0)
    psi = basis.evaluate(np.array([zc]))[0]
    if not 0.0 < z < 1.0:
        return psi, np.zeros_like(psi)
    h = DERIVATIVE_STEP
    both = basis.evaluate(np.array([zc + h, zc - h]))
    return psi, (both[0] - both[1]) / (2 * h)


class BipFilter:
    """The EKF of one task (module docstring).

    Parameters
    ----------
    mean : ndarray, shape (D*N,)
        Prior weight mean (human dims normalised, then robot).
    cov : ndarray, shape (D*N, D*N)
        Prior weight covariance (symmetric positive definite).
    n_basis : int
    noise : ndarray, shape (P,)
        Observation noise variances of the human dims.
    rate_mean, rate_std : float
        Prior of the phase velocity (1/s).
    phase_std : float
        Prior standard deviation of the initial phase.
    process_noise : float
        q of the phase system (1/s^4).
    basis : GaussianBasis
    """

    def __init__(self, mean, cov, n_basis: int, noise, rate_mean: float, rate_std: float,
                 phase_std: float, process_noise: float, basis) -> None:
        n = mean.size + 2
        self.x = np.r_[0.0, rate_mean, mean]
        self.P = np.zeros((n, n))
        self.P[0, 0], self.P[1, 1] = phase_std**2, rate_std**2
        self.P[2:, 2:] = cov
        self.N, self.noise, self.q = int(n_basis), np.asarray(noise), process_noise
        self.basis = basis
        self.time = 0.0
        self.log_likelihood = 0.0

    def predict(self, t: float) -> None:
        """Advance the phase system to time ``t`` (s)."""
        dt = max(t - self.time, 0.0)
        self.time = max(t, self.time)
        if dt == 0.0:
            return
        P = self.P
        self.x[0] += self.x[1] * dt
        P[0, :] += dt * P[1, :]                     # F P
        P[:, 0] += dt * P[:, 1]                     # (F P) F^T
        P[:2, :2] += self.q * np.array([[dt**4 / 4, dt**3 / 2], [dt**3 / 2, dt**2]])
        self._clip()

    def correct(self, y: FloatArray) -> None:
        """EKF update on one observation ``y`` (P,), NaN where unobserved."""
        obs = np.flatnonzero(np.isfinite(y))
        if obs.size == 0:
            return
        N, phi = self.N, float(self.x[0])
        psi, dpsi = basis_and_derivative(self.basis, phi)
        W = self.x[2:].reshape(-1, N)[obs]                       # (m, N)
        h = W @ psi
        g = W @ dpsi                                             # dh/dphi
        # P H^T without forming H: the phase column and each observed dim's weight block
        blocks = self.P[:, 2:].reshape(self.P.shape[0], -1, N)[:, obs, :]
        PHt = np.outer(self.P[:, 0], g) + blocks @ psi           # (n, m)
        rows = PHt[2:].reshape(-1, N, obs.size)[obs]             # (m, N, m)
        S = np.outer(g, PHt[0]) + np.einsum("n,inj->ij", psi, rows)   # H P H^T
        S = 0.5 * (S + S.T) + np.diag(self.noise[obs])
        nu = y[obs] - h
        L = scipy.linalg.cho_factor(S, lower=True)
        K = scipy.linalg.cho_solve(L, PHt.T).T                   # (n, m)
        self.x += K @ nu
        self.P -= K @ PHt.T
        self.P = 0.5 * (self.P + self.P.T)
        logdet = 2.0 * np.log(np.diag(L[0])).sum()
        self.log_likelihood += -0.5 * (nu @ scipy.linalg.cho_solve(L, nu) + logdet
                                       + obs.size * np.log(2 * np.pi))
        self._clip()

    def _clip(self) -> None:
        self.x[0] = min(max(self.x[0], 0.0), 1.0)
        self.x[1] = max(self.x[1], MIN_RATE)


def rate_prior(durations: FloatArray) -> tuple[float, float]:
    """Mean and standard deviation (ddof 1) of the phase velocity 1/T_i (1/s) of demos."""
    rates = 1.0 / np.asarray(durations, dtype=float)
    return float(rates.mean()), float(rates.std(ddof=1)) if rates.size > 1 else 0.0


class BIPPredictor(MethodPredictor):
    """BIP behind the predictor interface: one :class:`BipFilter` per task (module docstring).

    Parameters
    ----------
    library : DemoLibrary
    dow_t : float
        Seconds between updates (the filter itself runs on every kept observation).
    phase_std : float
        Prior standard deviation of the initial phase (default 0.02).
    process_noise : float
        Relative phase-acceleration noise (default 1.0: see the module docstring).
    **options
        Of :class:`~sandbox.methods.base.MethodPredictor`.
    """

    name = "bip"

    def __init__(self, library, dow_t: float = 0.2, *, phase_std: float = 0.02,
                 process_noise: float = 1.0, **options) -> None:
        self.phase_std = check_positive(phase_std, "phase_std", allow_zero=True)
        self.process_noise = check_positive(process_noise, "process_noise", allow_zero=True)
        super().__init__(library, dow_t, **options)

    def _reset_method(self) -> None:
        model = self.library.model
        self.filters = []
        for k, task in enumerate(model.task_models):
            mean, std = rate_prior(self.library.durations[k])
            self.filters.append(BipFilter(task.weights.mean, task.weights.cov(),
                                          model.basis.n_basis, model.noise, mean, std,
                                          self.phase_std, self.process_noise * mean**4,
                                          model.basis))

    def estimate(self, t, times, values):
        self._feed_filters(t, times, values)
        return self._from_filters(t)

    def _from_filters(self, t: float):
        model = self.library.model
        N, PN = model.basis.n_basis, model.n_human * model.basis.n_basis

        def robot(k: int):
            f, reg = self.filters[k], model.task_models[k].weights.reg[model.n_human:]
            return robot_from_cov(f.x[2 + PN:], f.P[2 + PN:, 2 + PN:], reg, N)

        phases = [f.x[0] for f in self.filters]
        rates = [f.x[1] for f in self.filters]
        durations = [end_time(f.x[0], f.x[1], t) for f in self.filters]
        ll = np.array([f.log_likelihood for f in self.filters])
        return self._make_prediction(ll, durations, robot, phases, rates, t)
