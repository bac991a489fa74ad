"""Online predictors: the static baseline and Dynamic Interaction ProMPs (paper sec. 2-3).

Both are fed human observations as they arrive (:meth:`observe`) and can be
asked at any time for the robot command (:meth:`command`): the mean joint
targets and their covariance at time t. The command is a piecewise-linear plan
over time (:mod:`sandbox.core.plan`: interpolation, blending, jumps); the
observations are kept by :mod:`sandbox.core.stream`. Before the first update the
plan is the moment-matched mixture of the task priors (each at its mean
duration, weighted by p(k)).

* :class:`DynamicPredictor` updates every ``dow_t`` seconds (a dynamic
  observation window): it re-estimates the speed of every task, the task
  posterior and the conditioned robot distribution of the most probable task,
  then blends the new distribution into the plan from the update time on
  (eq. 16-18): the current plan with a falling sigmoid, the new one with a
  rising sigmoid centred ``blend_delay`` after the update.
* :class:`StaticPredictor` (Maeda et al. 2017) updates once, after observing a
  fraction ``ratio`` of the expected duration.

The plan before an update's time is never rewritten, so what was executed
stays executed (an update earlier than the last one is a ``ValueError``); each
update records the jump it caused in the command. Once
an update finds that the motion has ended (``until_end``), the task is held:
after the handover the human's motion is no longer evidence about which task
it was, and later updates only refine that task's timing and robot motion.

Sizes are bounded (:mod:`sandbox.core.limits`): times within ``max_time`` of the
start (an absolute clock timestamp is a ``ValueError``), at most
:data:`~sandbox.core.limits.MAX_PLAN_STEPS` plan knots, a speed lattice within
:data:`~sandbox.core.limits.MAX_LATTICE_FLOATS`. Observations outside the
range the model was fitted on (with a margin) are rejected and counted
(:attr:`~sandbox.core.updating.PredictorBase.n_rejected`), like NaN rows are skipped.
"""

from __future__ import annotations

import copy
from typing import TYPE_CHECKING

import numpy as np

from sandbox.core.updating import LIKELIHOODS, PredictorBase, Update
from sandbox.limits import BOUNDS
from sandbox.validation import check_choice, check_fraction, check_positive

if TYPE_CHECKING:
    from sandbox.core.model import IProMP

__all__ = ["LIKELIHOODS", "WINDOW_MODES", "DynamicPredictor", "StaticPredictor", "Update"]

WINDOW_MODES = ("all", "latest")


class DynamicPredictor(PredictorBase):
    """Dynamic Interaction ProMP: re-predict every ``dow_t`` seconds and blend.

    Parameters
    ----------
    model : IProMP
        A fitted model.
    dow_t : float
        Dynamic observation window (s, in (0, 60], :data:`sandbox.limits.BOUNDS`): an
        update every ``dow_t`` seconds of observation (the paper tests 1, 0.5, 0.2, 0.1).
    observe : sequence of str or str, optional
        Modalities the incoming rows carry (default: all the model's); any
        subset predicts, the others are marginalised. A name the model was not
        fitted with is a ``ValueError`` listing what it has.
    subsample : int
        Keep 1 of every ``subsample`` valid observations (at most
        :data:`~sandbox.core.limits.MAX_SUBSAMPLE`).
    window : {"all", "latest"}
        Each update uses all observations so far, or only its own window's.
    likelihood : {"joint", "marginal"}
        Joint likelihood of all observations, or product of per-step marginals.
    n_candidates : int
        Speed candidates per task (grid over +/- ``width`` prior std), 3 to
        :data:`~sandbox.core.limits.MAX_CANDIDATES`; the whole lattice must fit
        :data:`~sandbox.core.limits.MAX_LATTICE_FLOATS`.
    width : float
    refine_steps : int
        Parabolic refinement steps of the speed after the grid (0 to 100).
    dt : float
        Plan resolution (s); the plan holds at most
        :data:`~sandbox.core.limits.MAX_PLAN_STEPS` knots.
    blend_rate : float
        Gradient l of the activation sigmoids (1/s).
    blend_delay : float
        Delay (s) from an update to the centre of its sigmoids.
    blend : bool
        Blend each new prediction into the plan (False: replace it).
    horizon : float
        The plan reaches at least this far (s) past each update (holding the
        predicted end), e.g. for a controller that looks ahead.
    until_end : bool
        Hold the task once the motion has ended: when an update finds that the
        chosen task's motion was over before the update's time (with posterior
        probability >= ``end_prob``, from its grid of durations), its choice is
        the last one: the human's further motion (releasing, retracting,
        occluded by the robot) is no longer evidence about which task it was.
        :attr:`ended` turns True and later updates keep that task and posterior,
        only re-estimating its timing and conditioning its robot motion on the
        hand. ``False`` re-chooses the task through the whole stream (on the
        recorded handovers recognition then falls after the handover). A
        closed-loop policy whose episode ends at the handover has no such
        motion to ignore, and :class:`~sandbox.episodes.policies.IProMPPolicy` turns it off.
    end_prob : float
        Probability of the motion being over that ends it (``until_end``).
        Default 0.5: every update between the meeting and the one that ends the
        motion scores more of the tail (the hand waiting, drifting back,
        overshooting, a frozen tracker) as if the motion held its final state,
        and can re-choose the task on it. Measured by leave-one-out on the
        recorded handovers with emulated tails (hand, dow_t 0.2 s): late decay
        0.000 instead of 0.006 on the recordings and 0.000 instead of 0.011 with
        the hand drifting back, recognition at the end 0.78 instead of 0.76;
        hand and arm drifting back: 0.029 instead of 0.063. The synthetic sets
        are unchanged; 0.3 cost the diverging set 0.02 of recognition at the end.
    incremental : bool
        Grow the likelihood's sufficient statistics with each observation
        (:mod:`sandbox.core.statistics`) so an update only factors small
        matrices; ``False`` computes everything at the update (same results).
    max_time : float
        Largest time (s since the motion started) accepted by :meth:`observe`
        and :meth:`update`; default :data:`~sandbox.core.limits.MAX_TIME_S`.
        Larger times (an absolute clock timestamp) are a ``ValueError``.

    Raises
    ------
    ValueError
        For an option that is not what is described above (a string, a
        boolean where a number is expected, ``inf``, out of range or over a limit).
    RuntimeError
        If the model is not fitted.

    Examples
    --------
    >>> import numpy as np
    >>> from sandbox.core import IProMP
    >>> from sandbox.data.synthetic import two_task_demos
    >>> demos = two_task_demos(10, np.random.default_rng(1))
    >>> model = IProMP(n_basis=21).fit(demos[1:])
    >>> pred = DynamicPredictor(model, dow_t=0.5)
    >>> for t, y in zip(demos[0].times, demos[0].human):
    ...     _ = pred.observe(t, y)
    >>> pred.task
    'left'
    """

    def __init__(self, model: IProMP, dow_t: float = 0.2, *, window: str = "all",
                 **options) -> None:
        self.dow_t = float(BOUNDS["dow_t"].check(dow_t, "dow_t"))   # the one table's range
        self.window = check_choice(window, "window", WINDOW_MODES)
        super().__init__(model, **options)

    def with_window(self, dow_t: float) -> DynamicPredictor:
        """A new predictor with this one's model and options but the window ``dow_t`` (s),
        as if just made (no observation, no update).

        It shares what depends only on the model and is never changed: the likelihood's
        :class:`~sandbox.core.likelihood.Scorer`, the speed lattice, the prior plan and the
        stream's bounds, which together cost more to build than an update (an
        evaluation runs every window over the same model).
        """
        other = copy.copy(self)
        other.dow_t = float(BOUNDS["dow_t"].check(dow_t, "dow_t"))
        other.stream = copy.copy(self.stream)    # reset() gives the copy its own lists
        other.reset()
        return other

    def reset(self) -> None:
        super().reset()
        self._next_update = self.dow_t

    def _maybe_update(self, t: float) -> Update | None:
        if not self.is_boundary(t):
            return None
        upd = self.update(t)
        self._next_update = self.next_boundary(t)
        return upd

    def is_boundary(self, t: float) -> bool:
        """Whether an observation at ``t`` triggers an update (a window boundary was reached)."""
        return t >= self._next_update - 1e-9   # tolerate accumulated float error in t

    def next_boundary(self, t: float) -> float:
        """The first window boundary after an update at ``t``."""
        return float((np.floor(t / self.dow_t + 1e-9) + 1) * self.dow_t)

    def _after_update(self) -> None:
        if self.window == "latest" and self._stats is not None:
            self._stats.reset()   # the next window's statistics start empty

    def _window(self, t: float):
        times, values = super()._window(t)
        if self.window == "latest" and self.updates:
            keep = times > self.updates[-1].time
            if keep.any():
                return times[keep], values[keep]
        return times, values


class StaticPredictor(PredictorBase):
    """Static IProMP baseline: one prediction after observing a fraction of the motion.

    Parameters
    ----------
    model : IProMP
        A fitted model.
    ratio : float
        Observed fraction f in (0, 1].
    expected_duration : float or None
        Duration (s) the fraction refers to. Offline evaluation passes the true
        duration, as the paper does; online (``None``) the prior mean duration
        :math:`\\sum_k p(k)\\mu_{\\alpha,k} T_{nom,k}` is used.
    **options
        As for :class:`DynamicPredictor` (``subsample``, ``likelihood``, ...).
    """

    def __init__(self, model: IProMP, ratio: float = 0.5, *, expected_duration: float | None = None,
                 **options) -> None:
        self.ratio = check_fraction(ratio, "ratio")
        self.expected_duration = (None if expected_duration is None
                                  else check_positive(expected_duration, "expected_duration"))
        super().__init__(model, **options)

    @property
    def decision_time(self) -> float:
        """When the one prediction is made (s)."""
        base = self.expected_duration
        if base is None:
            base = float(np.dot(self.model.priors,
                                [t.mean_duration for t in self.model.task_models]))
        return self.ratio * base

    def _maybe_update(self, t: float) -> Update | None:
        if self.updates or t < self.decision_time - 1e-9:
            return None
        return self.update(t)
