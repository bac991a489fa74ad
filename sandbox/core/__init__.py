"""The method: Interaction ProMPs with phase estimation and dynamic observation windows.

Imports only numpy and scipy.

Notation (as in the paper): P human dims (the observed modalities' dims, see
:mod:`~sandbox.core.modality`), Q robot dims, N basis functions,
D = (P+Q)N weights; :math:`\\psi` basis, :math:`\\Psi` design matrix, H observation
matrix, :math:`\\mu_\\omega, \\Sigma_\\omega` weight distribution,
:math:`\\Sigma_y` observation noise, :math:`\\alpha` speed factor (phase ratio),
:math:`T_{nom}` nominal duration, ``dow_t`` dynamic observation window.

Modules: :mod:`~sandbox.core.basis`, :mod:`~sandbox.core.promp`,
:mod:`~sandbox.core.model`, :mod:`~sandbox.core.interaction` (dense reference),
:mod:`~sandbox.core.likelihood` (fast path), :mod:`~sandbox.core.phase`,
:mod:`~sandbox.core.recognition`, :mod:`~sandbox.core.blending`,
:mod:`~sandbox.core.predictor` (with :mod:`~sandbox.core.stream`, the observation
stream), :mod:`~sandbox.core.modality`, :mod:`~sandbox.core.io` (with
:mod:`~sandbox.core.archive`, the checked ``.npz`` reader). At the public
boundary: :mod:`~sandbox.core.validation` (``check_*``, only ``ValueError``),
:mod:`~sandbox.core.limits` (every size limit, documented) and
:mod:`~sandbox.core.demos` (what ``fit`` accepts).

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

__all__ = [
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
