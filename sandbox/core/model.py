"""The fitted interaction model: one IProMP per task plus per-modality observation noise.

:class:`IProMP` is what users fit and save. For every task k it holds the weight
distribution over P human + Q robot dims (:mod:`sandbox.core.promp`), the nominal
duration :math:`T_{nom,k}` and the Gaussian prior of the speed factor
:math:`\\alpha = T / T_{nom,k}` (eq. 10); shared by all tasks are the basis, the
modalities (:mod:`sandbox.core.modality`), their observation noise
:math:`\\Sigma_y`, the scale of signal modalities and the task priors p(k).

Choices this project makes (DESIGN.md section 3):

* **A demonstration's motion ends when both partners have arrived**: the robot
  stays within ``settle_tol`` (rad) of its final configuration and the hand has
  come within ``arrive_tol`` (m) of its farthest reach (:func:`motion_end`).
  Recordings run on after the handover (0.6 +/- 0.3 s in the recorded set: the hand idles,
  retracts or is occluded), outside the motion's phase. Past its end a motion holds its
  final state (phase clipped at 1), robot and human alike: :mod:`sandbox.core.phase` scores
  observations past a candidate's end so (``post_end``: :mod:`sandbox.core.posthold`).
  ``settle_tol=None, arrive_tol=None`` keeps whole recordings (the paper's
  convention). The robot's part ends where it settles (``robot_tol``, :func:`fit_one`).
* :math:`T_{nom,k}` is the mean motion duration of task k, so :math:`\\mu_\\alpha = 1`
  and :math:`\\sigma_\\alpha` is the spread of :math:`T_i / T_{nom,k}` (ddof 1,
  floored at ``min_alpha_std``).
* **Signal modalities are normalised** (e.g. EMG envelopes): each signal dim is
  divided by its standard deviation over all samples of the training demos
  (:attr:`IProMP.scale`; 1 for positions). Only the training demos reach it
  (:meth:`IProMP.fit_demo_fits` pools per-demo moments), and it is stored with
  the model; predictors divide incoming signal values by it.
* :math:`\\Sigma_y` is diagonal: the residuals of each training demo's own basis
  fit of the human dims (normalised units), pooled over demos and tasks, divided
  by the residual degrees of freedom (valid samples minus N per demo and dim),
  scaled by ``noise_scale`` and floored per modality: ``noise_floor`` (m) for
  positions, ``signal_floor`` (normalised) for signals, or ``noise_floors[name]``.
  The residuals measure how far a track departs from a smooth N-basis curve; the
  floor, what a live track departs from the model by, which smoothed demos cannot
  show. A position floor is ``max(noise_floor, k x jitter)``, k = ``jitter_floor``, of
  the demos' raw jitter (:mod:`sandbox.core.jitter`). ``condition_floor`` gives the
  robot's conditioning its own noise :math:`\\Sigma_c` (:mod:`sandbox.core.condfloor`).
* The robot part is joint angles (rad) or, ``robot_space == "task"`` (taken from
  the demos), a position (m); the core treats both alike (tolerances in its units).
* The regulariser :math:`\\Lambda` (see :mod:`sandbox.core.promp`) is relative:
  for a robot dim, ``regularizer`` x the mean variance of its weights across
  the task's demos; for the human dims of modality m the same overall size
  (``regularizer`` x the mean weight variance of m's dims pooled over tasks)
  split across m's dims in proportion to :math:`\\Sigma_y`. That keeps
  :math:`\\kappa_m = \\lambda_p/\\sigma_p^2` equal for every dim of a modality and
  every task, which lets the likelihood share one factorisation per speed
  candidate and modality across dims and tasks; a modality's :math:`\\kappa_m`
  does not depend on the other modalities, so a model fitted on several
  modalities and observed through some of them equals the model fitted on
  those alone.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from sandbox.core.basis import GaussianBasis
from sandbox.core.condfloor import check_condition_floor, condition_noise
from sandbox.core.demos import as_demo_list, check_demo, check_demos, check_spread, modalities_of
from sandbox.core.fitchecks import (
    check_fits,
    check_floor,
    check_floor_names,
    check_robot_space,
    check_tolerance,
)
from sandbox.core.fitting import (
    DemoFit,
    DemonstrationLike,
    TaskModel,  # noqa: F401 - re-exported (sandbox.core)
    by_task,
    fit_one,
    motion_end,
    observation_noise,
    settle_index,
    signal_scale,
    task_models,
    task_priors,
)
from sandbox.core.floorsearch import check_noise_floor, model_floors
from sandbox.core.io import model_from_file, read_model, save_model
from sandbox.core.jitter import JITTER_FACTOR, demo_jitter
from sandbox.core.limits import MAX_DURATION_S, MAX_RELATIVE, check_alpha_std
from sandbox.core.modality import Modality
from sandbox.core.posthold import check_post_end, model_post_var, with_tail
from sandbox.core.shrinkage import check_shrinkage
from sandbox.core.spanreg import check_span_reg, model_span
from sandbox.limits import BOUNDS
from sandbox.validation import FloatArray, check_mapping, check_number, check_positive

if TYPE_CHECKING:
    from sandbox.core.calibration import Calibration

#: Default noise floor of signal modalities, in their normalised units (see IProMP).
SIGNAL_FLOOR = 1.0


class IProMP:
    """Interaction ProMPs for several tasks, fitted from paired demonstrations.

    Parameters
    ----------
    n_basis : int
        Basis functions per dim (N). Default 21, chosen by leave-one-out on the recorded
        handovers (``tune``; 15, 21 and 31 within noise; the paper uses 31).
    basis_width : float or None
        Variance of each basis function in phase units (see :class:`GaussianBasis`).
    basis_margin : float
        Centres spread over ``[-margin, 1 + margin]``.
    normalized_basis : bool
        Use normalised basis functions (default): plain Gaussians (eq. 1) without a
        margin misfit the ends of a motion, where the handover happens, by cm.
    regularizer : float
        Relative size of the weight-covariance regulariser (module docstring), in
        [:data:`~sandbox.core.limits.MIN_REGULARIZER`, :data:`~sandbox.core.limits.MAX_RELATIVE`]
        (``noise_scale`` and ``ridge`` too).
    span_reg : float, "auto" or None
        Raise each modality's regulariser to a factor of its weights' out-of-span variance
        (:mod:`sandbox.core.spanreg`; :attr:`span_report`); ``"auto"``: the factor per
        modality by a held-out score on the training demos; None: the regulariser alone.
    post_end : float, "span" or None
        Observations past a candidate's end share a held offset (:mod:`sandbox.core.posthold`,
        :attr:`post_var`): c x its learned variance, "span" adding the end's; None: today's.
    noise_scale : float
        Multiplies the estimated observation noise :math:`\\Sigma_y`.
    noise_floor : float
        Lowest :math:`\\sigma_p` of position modalities (m). Default 2 cm (leave-one-out on the
        recorded handovers: trusting observations more made every prediction worse). ``"auto"``:
        each position modality's floor from a grid (2 to 40 mm) by a held-out score on the
        training demos (:mod:`sandbox.core.floorsearch`; scores: :attr:`floor_scores`).
    condition_floor : float, "auto" or None
        A second floor (m) for conditioning the robot (eq. 7-9; :attr:`condition_noise`), the
        likelihood keeping ``noise_floor``; ``"auto"``: learnt (:mod:`sandbox.core.condfloor`).
    jitter_floor : float or None
        k: a position modality's floor is ``max(noise_floor, k x its jitter)``
        (:mod:`sandbox.core.jitter`; default :data:`~sandbox.core.jitter.JITTER_FACTOR`);
        None: ``noise_floor``. Not used by ``noise_floor="auto"``; ``noise_floors`` wins.
    signal_floor : float
        Lower bound of :math:`\\sigma_p` of signal modalities (normalised: fractions of sd).
    noise_floors : mapping of str to float, optional
        Per-modality floors (in the modality's normalised units) overriding the two
        above, for modalities of the demos; each in [:data:`~sandbox.core.limits.MIN_NOISE_STD`,
        its entry of :data:`sandbox.limits.BOUNDS`] (``noise_floor``: 1 m; others: 100).
    settle_tol, arrive_tol : float or None
        The motion ends once the robot stays within ``settle_tol`` (rad) of its final pose
        and the hand within ``arrive_tol`` (m) of its farthest reach (:func:`motion_end`);
        None for both: whole recordings.
    robot_tol : float or None
        The robot's part ends once within this distance (rad) of its final pose for
        good, not before the motion's end (None: at it); not stored in model files.
    min_alpha_std : float
        Lower bound of :math:`\\sigma_\\alpha`, in [limits.MIN_ALPHA_STD, limits.MAX_ALPHA_STD].
    shrinkage : {"auto", "none", "robot"}
        ``"auto"``: each task's weight covariance shrunk toward the tasks' pooled one
        (:mod:`sandbox.core.shrinkage`; :attr:`shrinkage_used`); ``"none"``: its own;
        ``"robot"``: shrunk only where it conditions the robot (eq. 8).
    ridge : float
        Relative ridge of the per-demo weight fit (eq. 2).
    priors : mapping of str to float, optional
        Task priors p(k); uniform by default, normalised after fitting.
    max_duration : float
        Longest demonstration :meth:`fit` accepts (s); default
        :data:`~sandbox.core.limits.MAX_DURATION_S` (a hint names ms or ns spans).

    Raises
    ------
    ValueError
        For any option not as described above (a string, a boolean, a number out of range).

    Examples
    --------
    >>> import numpy as np
    >>> from sandbox.data.synthetic import two_task_demos
    >>> model = IProMP(n_basis=15).fit(two_task_demos(5, np.random.default_rng(0)))
    >>> model.tasks
    ('left', 'right')
    >>> [m.name for m in model.modalities]
    ['hand']
    """

    def __init__(
        self,
        n_basis: int = 21,
        *,
        basis_width: float | None = None,
        basis_margin: float = 0.0,
        normalized_basis: bool = True,
        regularizer: float = 1e-3,
        span_reg: float | str | None = None,
        post_end: float | str | None = None,
        noise_scale: float = 1.0,
        noise_floor: float | str = 0.02,
        condition_floor: float | str | None = None,
        signal_floor: float = SIGNAL_FLOOR,
        noise_floors: Mapping[str, float] | None = None,
        jitter_floor: float | None = JITTER_FACTOR,
        settle_tol: float | None = 0.05,
        arrive_tol: float | None = 0.02,
        robot_tol: float | None = 0.01,
        min_alpha_std: float = 0.02,
        shrinkage: str = "none",
        ridge: float = 1e-8,
        priors: Mapping[str, float] | None = None,
        max_duration: float = MAX_DURATION_S,
    ) -> None:
        self.basis = GaussianBasis(n_basis, basis_width, basis_margin, normalized_basis)
        self.regularizer = float(BOUNDS["regularizer"].check(regularizer, "regularizer"))
        self.span_reg = check_span_reg(span_reg)
        self.span_report: dict[str, dict] = {}   #: of span_reg: v_m, c_m (and scores) per modality
        self.post_end = check_post_end(post_end)
        self.post_var: FloatArray | None = None   #: s_m^2 per modality (posthold.py), None: off
        self.noise_scale = check_positive(noise_scale, "noise_scale", high=MAX_RELATIVE)
        self.noise_floor = check_noise_floor(noise_floor, check_floor)
        self.floor_scores: dict[str, dict[float, float]] = {}   #: of noise_floor="auto"
        self.condition_floor = check_condition_floor(condition_floor, check_floor)
        self.condition_scores: dict[str, dict[float, float]] = {}   #: of its "auto"
        self.condition_noise: FloatArray | None = None   #: Sigma_c (P,), None: Sigma_y
        self.signal_floor = check_floor(signal_floor, "signal_floor", "signal_floor")
        self.noise_floors = {k: check_floor(v, f"noise_floors[{k!r}]", "noise_floors")
                             for k, v in check_mapping(noise_floors, "noise_floors").items()}
        self.jitter_floor = (None if jitter_floor is None else BOUNDS["jitter_floor"].check(
            jitter_floor, "jitter_floor", or_null=True))
        self.settle_tol = check_tolerance(settle_tol, "settle_tol")
        self.arrive_tol = check_tolerance(arrive_tol, "arrive_tol")
        self.robot_tol = None if robot_tol is None else check_positive(robot_tol, "robot_tol")
        self.min_alpha_std = check_alpha_std(min_alpha_std, "min_alpha_std")
        self.shrinkage = check_shrinkage(shrinkage)
        #: By task, the shrinkage intensity in [0, 1] of the last fit (not saved).
        self.shrinkage_used: dict[str, float] = {}
        self.ridge = check_positive(ridge, "ridge", allow_zero=True, high=MAX_RELATIVE)
        self.max_duration = check_positive(max_duration, "max_duration")
        self._prior_spec = (None if priors is None else
                            {k: check_number(v, f"priors[{k!r}]", low=0.0)
                             for k, v in check_mapping(priors, "priors").items()})
        self._fitted = False
        self.calibration: Calibration | None = None
        #: What a session taught besides the model (JSON-able; e.g. :mod:`sandbox.data.geometry`).
        self.session: dict[str, Any] = {}
        self.robot_space = "joint"   #: what the robot dims are: "joint" (rad) or "task" (m)

    # ------------------------------------------------------------------ fit
    def fit(self, demos: Sequence[DemonstrationLike]) -> IProMP:
        """Fit one model per task. Returns ``self``.

        Parameters
        ----------
        demos : sequence of Demonstration
            At least two per task, all with the same P, Q and modalities, each
            valid as :mod:`sandbox.core.demos` describes (times in seconds
            spanning at most ``max_duration``).

        Raises
        ------
        ValueError
            For an invalid demonstration (saying which and why), a task with
            fewer than two demonstrations, or a task whose demonstrations do not
            differ (:func:`~sandbox.core.demos.check_spread`).
        """
        demos = as_demo_list(demos)
        check_demos(demos, self.max_duration)
        return self.fit_demo_fits([self.demo_fit(d) for d in demos], demos[0])

    def demo_fit(self, demo: DemonstrationLike) -> DemoFit:
        """Per-demo part of the fit: weights, residuals and moments of the human dims, duration.

        Only the motion is used: the samples up to :func:`motion_end`. The
        demonstration is checked as :meth:`fit` checks it (``ValueError``).
        """
        times, human, robot = check_demo(demo, "demo", self.max_duration)
        end = self.motion_end(times, robot, human)
        jitter = demo_jitter(demo, times, human, modalities_of(demo, human.shape[1]))
        return with_tail(fit_one(str(demo.task), times, human[:end + 1], robot, self.basis,
                                 self.ridge, settle_index(robot, self.robot_tol, end), jitter),
                         human, end)

    def motion_end(self, times, robot, human) -> int:
        """:func:`motion_end` with this model's tolerances."""
        return motion_end(times, robot, self.settle_tol, human, self.arrive_tol)

    def fit_demo_fits(self, fits: Sequence[DemoFit], names_from=None) -> IProMP:
        """Fit from per-demo parts (:meth:`demo_fit`); cheap, e.g. for leave-one-out.

        ``names_from`` is a demonstration whose dim names and modalities the
        model keeps. Everything the model learns, the scale of signal
        modalities included, comes from ``fits`` alone.
        """
        check_fits(fits, self.basis.n_basis)
        weights, durations = by_task(fits)
        P = fits[0].residual.size
        Q = fits[0].weights.size // self.basis.n_basis - P
        modalities = modalities_of(names_from, P)
        check_floor_names(self.noise_floors, modalities)
        scale = signal_scale(modalities, np.sum([f.moments for f in fits], axis=0))
        self.floors_used = self.floors(modalities, fits, scale)
        sigma2 = observation_noise(fits, scale, self.floors_used, self.noise_scale)
        cond = condition_noise(self, modalities, fits, scale, self.floors_used)
        divide = np.r_[scale, np.ones(Q)].repeat(self.basis.n_basis)
        arrays = {k: np.array(v) / divide for k, v in weights.items()}
        for k, w in arrays.items():
            check_spread(k, w)
        floor = model_span(self, modalities, arrays, sigma2, fits, scale)
        self._set_fit(arrays, durations, sigma2, P, Q, names_from, modalities, scale, floor)
        self.condition_noise, self.post_var = cond, model_post_var(self, fits, scale)
        return self

    def floors(self, modalities: Sequence[Modality], fits: Sequence[DemoFit] = (),
               scale: FloatArray | None = None) -> FloatArray:
        """Noise floors (P,), normalised: :func:`~sandbox.core.floorsearch.model_floors`."""
        return model_floors(self, modalities, fits, scale)

    def _set_fit(self, weights, durations, sigma2, P, Q, first, modalities, scale,
                 reg_floor=None) -> None:
        tasks, self.shrinkage_used = task_models(
            weights, durations, sigma2, modalities, self.regularizer, self.basis.n_basis,
            self.min_alpha_std, self.shrinkage, reg_floor)
        self.task_models = tasks
        self.noise = sigma2
        self.scale = np.asarray(scale, dtype=np.float64)
        self.modalities = tuple(modalities)
        self.n_human, self.n_robot = P, Q
        self.human_names = tuple(d for m in self.modalities for d in m.dims)
        self.robot_names = tuple(getattr(first, "robot_names", ()) or ())
        self.robot_space = check_robot_space(getattr(first, "robot_space", "joint"))
        self.priors = task_priors([t.name for t in tasks], self._prior_spec)
        self.calibration = None          # of a previous fit, if any: no longer valid
        self.session = {}                # likewise
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

    @property
    def modality_names(self) -> tuple[str, ...]:
        """Names of the modalities the model was fitted on, in order."""
        self._require_fit()
        return tuple(m.name for m in self.modalities)

    def task_index(self, task: str) -> int:
        """Index of a task by name."""
        try:
            return self.tasks.index(task)
        except ValueError:
            raise ValueError(f"task: expected one of {list(self.tasks)}, got {task!r}") from None

    def with_priors(self, priors: Mapping[str, float]) -> IProMP:
        """Set new task priors p(k) (normalised); returns ``self``."""
        self._require_fit()
        spec = {k: check_number(v, f"priors[{k!r}]", low=0.0)
                for k, v in check_mapping(priors, "priors").items()}
        self.priors = task_priors(self.tasks, spec)
        return self

    def calibrate(self, demos, streams=None, **options):
        """Calibrate the familiarity of this model, fitted on ``demos`` (leave-one-out): sets
        and returns :attr:`calibration` (:func:`sandbox.core.familiarity.calibrate`: ``streams``,
        options); without one (a fresh fit, a file without one) ``familiarity`` is None."""
        from sandbox.core.familiarity import calibrate

        self._require_fit()
        return calibrate(self, demos, streams, **options)

    def save(self, path) -> None:
        """Save as ``.npz`` + JSON metadata (no pickle); see :mod:`sandbox.core.io`."""
        self._require_fit()
        save_model(self, path)

    @classmethod
    def load(cls, path) -> IProMP:
        """Load a model saved by :meth:`save`; refuses corrupt or foreign files (``ValueError``)."""
        content = read_model(path)
        try:
            return model_from_file(cls, content)
        except ValueError as error:   # hyperparameters the constructor refuses
            raise ValueError(f"model file {str(path)!r}: {error}") from None

    def __repr__(self) -> str:
        if not self._fitted:
            return f"IProMP(n_basis={self.basis.n_basis}, unfitted)"
        return (f"IProMP(tasks={list(self.tasks)}, observe={list(self.modality_names)}, "
                f"P={self.n_human}, Q={self.n_robot}, n_basis={self.basis.n_basis})")

