"""The fitted interaction model: one IProMP per task plus shared observation noise.

:class:`IProMP` is what users fit and save. For every task k it holds the
weight distribution over P human + Q robot dims (:mod:`sandbox.core.promp`), the
nominal duration :math:`T_{nom,k}` and the Gaussian prior of the speed factor
:math:`\\alpha = T / T_{nom,k}` (paper eq. 11); shared by all tasks are the
basis, the human observation noise :math:`\\Sigma_y` and the task priors p(k).

Choices this project makes (DESIGN.md section 3):

* :math:`T_{nom,k}` is the mean demo duration of task k, so :math:`\\mu_\\alpha = 1`
  and :math:`\\sigma_\\alpha` is the spread of :math:`T_i / T_{nom,k}` (ddof 1,
  floored at ``min_alpha_std``).
* :math:`\\Sigma_y` is diagonal and estimated from the data: the residuals of each
  training demo's own basis fit of the human dims, pooled over demos and tasks,
  divided by the residual degrees of freedom (sum of valid samples minus N per
  demo and dim), scaled by ``noise_scale`` and floored at ``noise_floor``.
  The residuals measure how far a hand track departs from a smooth N-basis
  curve (sensor noise, 30 Hz steps, jitter); the floor (2 cm by default,
  chosen by cross-validation) stands for what a live track departs from the
  model by, which smoothed training demos cannot show.
* The regulariser :math:`\\Lambda` (see :mod:`sandbox.core.promp`) is relative:
  for a robot dim, ``regularizer`` x the mean variance of its weights across
  the task's demos; for the human dims the same overall size (``regularizer`` x
  the mean human weight variance pooled over tasks) split across dims in
  proportion to :math:`\\Sigma_y`. That keeps :math:`\\lambda_p/\\sigma_p^2`
  equal for every human dim and task, which lets the likelihood share one
  factorisation per speed candidate across dims and tasks.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from sandbox.core.basis import GaussianBasis
from sandbox.core.promp import WeightDistribution, fit_weights
from sandbox.core.validation import FloatArray, check_array, check_positive


class DemonstrationLike(Protocol):
    """What :meth:`IProMP.fit` needs of a demonstration (see ``sandbox.data.Demonstration``)."""

    times: Any
    human: Any
    robot: Any
    task: str


@dataclass(frozen=True, eq=False)
class TaskModel:
    """One task's interaction primitive.

    Attributes
    ----------
    name : str
    weights : WeightDistribution
        Over the P human dims followed by the Q robot dims.
    nominal_duration : float
        :math:`T_{nom}` (s).
    alpha_mean, alpha_std : float
        Prior of the speed factor :math:`\\alpha = T/T_{nom}`.
    n_demos : int
    """

    name: str
    weights: WeightDistribution
    nominal_duration: float
    alpha_mean: float
    alpha_std: float
    n_demos: int

    @property
    def mean_duration(self) -> float:
        """Prior mean duration :math:`\\mu_\\alpha T_{nom}` (s)."""
        return self.alpha_mean * self.nominal_duration


@dataclass(frozen=True, eq=False)
class DemoFit:
    """What :meth:`IProMP.demo_fit` keeps of one demonstration.

    Attributes
    ----------
    task : str
    weights : ndarray, shape ((P+Q)*N,)
    residual : ndarray, shape (P,)
        Sum of squared residuals of the human dims' basis fit.
    dof : ndarray, shape (P,)
        Their degrees of freedom (valid samples - N).
    duration : float
        (s)
    """

    task: str
    weights: FloatArray
    residual: FloatArray
    dof: FloatArray
    duration: float


class IProMP:
    """Interaction ProMPs for several tasks, fitted from paired demonstrations.

    Parameters
    ----------
    n_basis : int
        Basis functions per dim (N). Default 21, chosen by leave-one-out on the
        recorded handovers (``python -m sandbox tune``; 15, 21 and 31 were within
        noise of each other; the paper uses 31).
    basis_width : float or None
        Variance of each basis function in phase units (see :class:`GaussianBasis`).
    basis_margin : float
        Centres spread over ``[-margin, 1 + margin]``.
    normalized_basis : bool
        Use normalised basis functions (default). Plain Gaussians (the paper's
        eq. 1) without a margin misfit the ends of a motion by centimetres, where
        the handover happens; normalised ones represent constants exactly.
    regularizer : float
        Relative size of the weight-covariance regulariser (module docstring);
        default chosen by leave-one-out on the recorded handovers.
    noise_scale : float
        Multiplies the estimated observation noise :math:`\\Sigma_y`.
    noise_floor : float
        Lower bound of every :math:`\\sigma_p` (m). Default 2 cm, chosen by
        leave-one-out on the recorded handovers: smoothed training demos leave
        ~1 mm residuals, but a live, causally filtered track departs from what
        the model can explain by ~2 cm (tracker jumps and occlusions, motion the
        demos do not span); trusting observations more made every prediction
        worse, including the oracle's.
    min_alpha_std : float
        Lower bound of :math:`\\sigma_\\alpha`.
    ridge : float
        Relative ridge of the per-demo weight fit (eq. 2).
    priors : mapping of str to float, optional
        Task priors p(k); uniform by default. Normalised after fitting.

    Examples
    --------
    >>> import numpy as np
    >>> from sandbox.data.synthetic import two_task_demos
    >>> model = IProMP(n_basis=15).fit(two_task_demos(5, np.random.default_rng(0)))
    >>> model.tasks
    ('left', 'right')
    """

    def __init__(
        self,
        n_basis: int = 21,
        *,
        basis_width: float | None = None,
        basis_margin: float = 0.0,
        normalized_basis: bool = True,
        regularizer: float = 1e-3,
        noise_scale: float = 1.0,
        noise_floor: float = 0.02,
        min_alpha_std: float = 0.02,
        ridge: float = 1e-8,
        priors: Mapping[str, float] | None = None,
    ) -> None:
        self.basis = GaussianBasis(n_basis, basis_width, basis_margin, normalized_basis)
        self.regularizer = check_positive(regularizer, "regularizer")
        self.noise_scale = check_positive(noise_scale, "noise_scale")
        self.noise_floor = check_positive(noise_floor, "noise_floor")
        self.min_alpha_std = check_positive(min_alpha_std, "min_alpha_std")
        self.ridge = check_positive(ridge, "ridge", allow_zero=True)
        self._prior_spec = dict(priors) if priors is not None else None
        self._fitted = False

    # ------------------------------------------------------------------ fit
    def fit(self, demos: Sequence[DemonstrationLike]) -> IProMP:
        """Fit one model per task. Returns ``self``.

        Parameters
        ----------
        demos : sequence of Demonstration
            At least two per task, all with the same P, Q (and dim names).
        """
        _check_demos(demos)
        return self.fit_demo_fits([self.demo_fit(d) for d in demos], demos[0])

    def demo_fit(self, demo: DemonstrationLike) -> DemoFit:
        """Per-demo part of the fit: weights, residuals of the human dims, duration."""
        P, n = np.shape(demo.human)[1], self.basis.n_basis
        times = np.asarray(demo.times, dtype=np.float64)
        z = (times - times[0]) / (times[-1] - times[0])
        human = np.asarray(demo.human, dtype=np.float64)
        wd = fit_weights(z, np.hstack([human, demo.robot]), self.basis, self.ridge)
        err = human - self.basis.evaluate(z) @ wd[:P].T
        ok = np.isfinite(err)
        return DemoFit(str(demo.task), wd.ravel(), (np.where(ok, err, 0.0) ** 2).sum(axis=0),
                       np.maximum(ok.sum(axis=0) - n, 1).astype(float),
                       float(times[-1] - times[0]))

    def fit_demo_fits(self, fits: Sequence[DemoFit], names_from=None) -> IProMP:
        """Fit from per-demo parts (:meth:`demo_fit`); cheap, e.g. for leave-one-out.

        ``names_from`` is a demonstration whose dim names the model keeps.
        """
        weights: dict[str, list] = {}
        durations: dict[str, list] = {}
        for f in fits:
            weights.setdefault(f.task, []).append(f.weights)
            durations.setdefault(f.task, []).append(f.duration)
        small = [k for k, v in weights.items() if len(v) < 2]
        if small:
            raise ValueError(f"demos: expected at least two demonstrations per task, "
                             f"got one for {small}")
        residual = np.sum([f.residual for f in fits], axis=0)
        dof = np.sum([f.dof for f in fits], axis=0)
        P = residual.size
        Q = fits[0].weights.size // self.basis.n_basis - P
        sigma2 = np.maximum(self.noise_scale * residual / dof, self.noise_floor**2)
        self._set_fit({k: np.array(v) for k, v in weights.items()},
                      {k: np.array(v) for k, v in durations.items()}, sigma2, P, Q, names_from)
        return self

    def _set_fit(self, weights, durations, sigma2, P, Q, first) -> None:
        n = self.basis.n_basis
        dists = {
            k: WeightDistribution.from_weights(w, self.regularizer, n) for k, w in weights.items()
        }
        human_var = np.mean([d.reg[:P] / self.regularizer for d in dists.values()])
        kappa = self.regularizer * human_var / sigma2.mean()
        tasks = []
        for k, dist in dists.items():
            reg = dist.reg.copy()
            reg[:P] = kappa * sigma2
            dist = WeightDistribution(dist.mean, dist.factor, reg, n)
            T = durations[k]
            t_nom = float(T.mean())
            a_std = float(np.std(T / t_nom, ddof=1)) if T.size > 1 else 0.0
            tasks.append(
                TaskModel(k, dist, t_nom, 1.0, max(a_std, self.min_alpha_std), int(T.size))
            )
        self.task_models = tuple(tasks)
        self.noise = sigma2
        self.n_human, self.n_robot = P, Q
        self.human_names = tuple(getattr(first, "human_names", ()) or ())
        self.robot_names = tuple(getattr(first, "robot_names", ()) or ())
        self.priors = _priors([t.name for t in tasks], self._prior_spec)
        self._fitted = True

    # ------------------------------------------------------------ accessors
    def _require_fit(self) -> None:
        if not self._fitted:
            raise RuntimeError(
                "this IProMP is not fitted yet: call fit(demos) or IProMP.load(path)"
            )

    @property
    def is_fitted(self) -> bool:
        """Whether :meth:`fit` (or :meth:`load`) has been called."""
        return self._fitted

    @property
    def tasks(self) -> tuple[str, ...]:
        """Task names in model order."""
        self._require_fit()
        return tuple(t.name for t in self.task_models)

    def task_index(self, task: str) -> int:
        """Index of a task by name."""
        try:
            return self.tasks.index(task)
        except ValueError:
            raise ValueError(f"task: expected one of {list(self.tasks)}, got {task!r}") from None

    def with_priors(self, priors: Mapping[str, float]) -> IProMP:
        """Set new task priors p(k) (normalised); returns ``self``."""
        self._require_fit()
        self.priors = _priors(self.tasks, dict(priors))
        return self

    def save(self, path) -> None:
        """Save as ``.npz`` + JSON metadata (no pickle); see :mod:`sandbox.core.io`."""
        from sandbox.core.io import save_model

        self._require_fit()
        save_model(self, path)

    @classmethod
    def load(cls, path) -> IProMP:
        """Load a model saved by :meth:`save`; refuses corrupt or foreign files."""
        from sandbox.core.io import load_model

        return load_model(path)

    def __repr__(self) -> str:
        if not self._fitted:
            return f"IProMP(n_basis={self.basis.n_basis}, unfitted)"
        return (
            f"IProMP(tasks={list(self.tasks)}, P={self.n_human}, Q={self.n_robot}, "
            f"n_basis={self.basis.n_basis})"
        )


def _check_demos(demos: Sequence[DemonstrationLike]) -> None:
    """Shapes, finiteness and consistent P, Q (the per-task count is checked by the fit)."""
    if demos is None or len(demos) == 0:
        raise ValueError("demos: expected at least two demonstrations per task, got none")
    P = Q = None
    for i, d in enumerate(demos):
        for attr in ("times", "human", "robot", "task"):
            if not hasattr(d, attr):
                raise ValueError(f"demos[{i}]: expected a Demonstration, missing '{attr}'")
        h = check_array(d.human, f"demos[{i}].human", 2, allow_nan=True)
        r = check_array(d.robot, f"demos[{i}].robot", 2)
        t = check_array(d.times, f"demos[{i}].times", 1, shape=(h.shape[0],), min_len=2)
        if r.shape[0] != t.size or not np.all(np.diff(t) > 0):
            raise ValueError(f"demos[{i}]: expected increasing times matching {t.size} rows")
        P = h.shape[1] if P is None else P
        Q = r.shape[1] if Q is None else Q
        if (h.shape[1], r.shape[1]) != (P, Q):
            raise ValueError(
                f"demos[{i}]: expected P={P}, Q={Q} like the first demo, "
                f"got P={h.shape[1]}, Q={r.shape[1]}"
            )


def _priors(tasks: Sequence[str], spec: Mapping[str, float] | None) -> FloatArray:
    if spec is None:
        return np.full(len(tasks), 1.0 / len(tasks))
    unknown = set(spec) - set(tasks)
    if unknown:
        raise ValueError(f"priors: unknown tasks {sorted(unknown)}; tasks are {list(tasks)}")
    p = np.array([float(spec.get(t, 0.0)) for t in tasks])
    if not np.all(np.isfinite(p)) or np.any(p < 0) or p.sum() <= 0:
        raise ValueError(f"priors: expected non-negative numbers with a positive sum, got {spec}")
    return p / p.sum()
