"""The method: Interaction ProMPs with phase estimation and dynamic observation windows.

Imports only numpy and scipy.

Notation (as in the paper): P human dims (the observed modalities' dims, see
:mod:`~sandbox.core.modality`), Q robot dims, N basis functions,
D = (P+Q)N weights; :math:`\\psi` basis, :math:`\\Psi` design matrix, H observation
matrix, :math:`\\mu_\\omega, \\Sigma_\\omega` weight distribution,
:math:`\\Sigma_y` observation noise, :math:`\\alpha` speed factor (phase ratio),
:math:`T_{nom}` nominal duration, ``dow_t`` dynamic observation window.

Modules: :mod:`~sandbox.core.basis`, :mod:`~sandbox.core.promp`,
:mod:`~sandbox.core.model` (with :mod:`~sandbox.core.fitting`, the steps of a fit),
:mod:`~sandbox.core.interaction` (dense reference),
:mod:`~sandbox.core.likelihood` (fast path; its linear algebra in
:mod:`~sandbox.core.factor`), :mod:`~sandbox.core.phase`,
:mod:`~sandbox.core.recognition`, :mod:`~sandbox.core.blending`,
:mod:`~sandbox.core.predictor` (with :mod:`~sandbox.core.updating`, the machinery both
predictors share, and :mod:`~sandbox.core.stream`, the observation stream),
:mod:`~sandbox.core.familiarity` (with :mod:`~sandbox.core.evidence`, its timing
statistics, :mod:`~sandbox.core.calibration` and :mod:`~sandbox.core.conformal`),
:mod:`~sandbox.core.modality`, :mod:`~sandbox.core.io` (with :mod:`~sandbox.core.archive`,
the checked ``.npz`` reader). At the public
boundary: :mod:`~sandbox.validation` (``check_*``, only ``ValueError``),
:mod:`~sandbox.core.limits` (every size limit, documented) and
:mod:`~sandbox.core.demos` (what ``fit`` accepts).

Equations
---------
Equation numbers are those of the compiled paper, which numbers 20 equations
(the LaTeX source in ``../shared/paper``, counted as LaTeX numbers them: every
``equation`` environment is one number, also when it holds an ``aligned`` or
``array`` block of several lines; the one ``eqnarray`` has one line, so one
number; ``\\label`` does not matter; there is no ``align``, no ``\\nonumber``
and no unnumbered display that would change the count). :data:`EQUATIONS` maps
each number to what it states and the functions that implement it; a
``# eq. N`` comment sits beside the implementing lines, and
``tests/core/test_equations.py`` checks both, and the count against the paper's
source when it is present.

References
----------
S. Duan, L. Chen, H. Wu, Y. Wang, X. Zhao, J. Rojas, "Dynamic Interaction
Probabilistic Movement Primitives", arXiv:1809.04215, 2018.
G. Maeda, M. Ewerton, G. Neumann, R. Lioutikov, J. Peters, "Phase estimation
for fast action recognition and trajectory generation in human-robot
collaboration", IJRR 36(13-14), 2017.
"""

from sandbox.core.basis import GaussianBasis
from sandbox.core.blending import blend, sigmoid_activations
from sandbox.core.inference import Prediction, predict
from sandbox.core.interaction import condition, log_marginal_likelihood, observation_matrix
from sandbox.core.modality import Modality
from sandbox.core.model import DemoFit, IProMP, TaskModel
from sandbox.core.phase import PhaseEstimate, estimate_phase
from sandbox.core.predictor import DynamicPredictor, StaticPredictor, Update
from sandbox.core.promp import WeightDistribution, fit_weights, trajectory_distribution
from sandbox.core.recognition import task_posterior

#: The paper's numbered equations: number -> (what it states, the functions implementing it,
#: as dotted paths; the metrics 19-20 live in :mod:`sandbox.eval`).
EQUATIONS: dict[int, tuple[str, tuple[str, ...]]] = {
    1: ("linear basis model y_t = psi_t^T omega + eps",
        ("sandbox.core.promp.trajectory_distribution",)),
    2: ("weights of one trajectory by least squares (here with a ridge)",
        ("sandbox.core.promp.fit_weights", "sandbox.core.promp._ridge_solve",
         "sandbox.core.fitting.fit_one")),
    3: ("design matrix Psi: basis functions at every step",
        ("sandbox.core.basis.GaussianBasis.evaluate",)),
    4: ("trajectory distribution: psi^T mu_w, psi^T Sigma_w psi (+ sigma_y)",
        ("sandbox.core.promp.trajectory_distribution", "sandbox.core.plan.Plan.prior")),
    5: ("state vector: P human dims, then Q robot dims",
        ("sandbox.core.fitting.fit_one",)),
    6: ("weight vector: all dims' weights concatenated",
        ("sandbox.core.fitting.fit_one",)),
    7: ("block-diagonal basis matrix H_t", ("sandbox.core.interaction.observation_matrix",)),
    8: ("Kalman conditioning of the weights on the observations",
        ("sandbox.core.interaction.condition", "sandbox.core.factor.condition_robot")),
    9: ("masked H: robot rows zero (unobserved)",
        ("sandbox.core.interaction.observation_matrix", "sandbox.core.interaction._masked")),
    10: ("speed factor alpha = T_i / T_nom",
         ("sandbox.core.fitting.task_models", "sandbox.core.phase.estimate_phase")),
    11: ("phase posterior p(alpha | y) ~ p(y | alpha) p(alpha)",
         ("sandbox.core.phase.estimate_phase",)),
    12: ("likelihood of the observations given alpha (weights integrated out)",
         ("sandbox.core.interaction.log_marginal_likelihood",
          "sandbox.core.likelihood.Scorer.joint")),
    13: ("MAP speed alpha* = argmax p(alpha | y)", ("sandbox.core.phase.estimate_phase",)),
    14: ("task posterior p(k | y) ~ p(y | theta_k, alpha*_k) p(k)",
         ("sandbox.core.recognition.task_posterior", "sandbox.core.inference.predict")),
    15: ("task likelihood at the MAP speed",
         ("sandbox.core.interaction.log_marginal_likelihood",
          "sandbox.core.recognition.task_posterior", "sandbox.core.inference.predict")),
    16: ("product of distributions with activations",
         ("sandbox.core.blending.blend_unchecked", "sandbox.core.plan.Plan.blended")),
    17: ("blended covariance and mean", ("sandbox.core.blending._product",)),
    18: ("rising and falling sigmoid activations",
         ("sandbox.core.blending.sigmoid_activations", "sandbox.core.plan._blend")),
    19: ("static - dynamic differences of e_p, e_q, e_phi",
         ("sandbox.eval.report.build_report",)),
    20: ("window-selection metric m(dow_t)", ("sandbox.eval.metrics.window_metric",)),
}

__all__ = [
    "EQUATIONS",
    "DemoFit",
    "DynamicPredictor",
    "GaussianBasis",
    "IProMP",
    "Modality",
    "PhaseEstimate",
    "Prediction",
    "StaticPredictor",
    "TaskModel",
    "Update",
    "WeightDistribution",
    "blend",
    "condition",
    "estimate_phase",
    "fit_weights",
    "log_marginal_likelihood",
    "observation_matrix",
    "predict",
    "sigmoid_activations",
    "task_posterior",
    "trajectory_distribution",
]
