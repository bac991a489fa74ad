"""Documented limits checked at the public boundary.

Nothing in the method needs unbounded sizes: a handover lasts seconds, a
trajectory has tens of basis functions. These limits turn a careless input
(a trial stamped in milliseconds, a stray 1e6 s timestamp) into a clear
``ValueError`` instead of a multi-gigabyte allocation. Each message names the
limit and, where it can be raised, how.

The bounds of the options a user sets (``n_basis``, ``n_candidates``,
``subsample``, the relative hyperparameters, the noise floors) are read from
the one table of :mod:`sandbox.limits`, which the command line, settings,
scenario and grid files check too.

Who checks what: :meth:`~sandbox.core.model.IProMP.fit` (durations, units,
values, dims, spread), the predictors (times, options, plan, lattice,
observations and their range), :meth:`~sandbox.core.model.IProMP.load` (file,
members, metadata, values). :func:`check_duration` and :func:`check_time` are
for loaders and callers that want the same checks and messages.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from sandbox.limits import BOUNDS
from sandbox.validation import check_number

#: Longest demonstration or trial accepted (s). Handovers last 1-10 s; a
#: minute leaves ample room. Raise it with ``max_duration=`` (``IProMP``).
MAX_DURATION_S = 60.0

#: Shortest median sample interval accepted (s): 10 kHz. Finer spacing on a
#: motion of human duration means the times are not in seconds.
MIN_MEDIAN_DT_S = 1e-4

#: Latest time a predictor accepts (s since the motion started): observations,
#: updates; also the longest task duration a model file may hold. A
#: closed-loop episode (scenario files allow up to 600 s) stays within it;
#: absolute clock timestamps (~1.7e9 s) do not. Raise it with the predictors'
#: ``max_time=``.
MAX_TIME_S = 600.0

#: Most basis functions per dim (N). The method uses 15-31; each likelihood
#: factorisation is N x N per speed candidate.
MAX_N_BASIS = int(BOUNDS["n_basis"].high)

#: Most speed candidates per task (``n_candidates``; default 50).
MAX_CANDIDATES = int(BOUNDS["n_candidates"].high)

#: Most floats a predictor's speed lattice may need for its likelihood
#: statistics: C durations x (N^2 per modality + K (R+1)^2), with K tasks of
#: rank <= R (256 MiB of float64). The default models need about 1e5.
MAX_LATTICE_FLOATS = 2**25

#: Most knots of a predictor's plan (its resolution ``dt`` over its length):
#: 1000 s at the default 0.01 s. Memory grows with Q^2 per knot (40 MB for
#: Baxter's 7 joints).
MAX_PLAN_STEPS = 100_000

#: Most observations a predictor keeps (after ``subsample``) before ``reset()``:
#: a minute at 333 kept rows per second, 1000 s at the 20 per second a
#: closed-loop policy keeps. A batch update allocates C x kept x N floats.
MAX_OBSERVATIONS = 20_000

#: Largest ``subsample`` (keep 1 of this many observations).
MAX_SUBSAMPLE = int(BOUNDS["subsample"].high)

#: Most human dims P and most robot dims Q of a model.
MAX_DIMS = 64

#: Largest magnitude of any demonstration value (m, rad or raw signal units):
#: no such quantity comes near it, and sums of squares of millions of samples
#: stay far from overflow.
MAX_ABS_VALUE = 1e9

#: A task's demonstrations must differ: the largest standard deviation of
#: their weights (normalised units) must exceed this fraction of the weights'
#: largest magnitude. Duplicated, constant or all-zero demos fall far below it
#: (round-off, ~1e-9 at most); demos that differ only by their duration and
#: sampling already reach ~1e-3.
MIN_RELATIVE_SPREAD = 1e-6

#: Margin (m) around the range a model's position modalities were fitted on
#: (its tasks' mean +/- 3 std over the motion): an observation farther out is
#: rejected (counted, skipped like a NaN).
POSITION_MARGIN_M = 10.0

#: Same margin for signal modalities, in their normalised units: 1e3 x the
#: training demos' standard deviation of the signal.
SIGNAL_MARGIN = 1e3

#: Smallest observation noise standard deviation (normalised units; 1e-12 m
#: for positions): the floor of the fit's noise floors, and of a model file's
#: noise (its square). Finer noise is not physical and would make the
#: likelihood overflow.
MIN_NOISE_STD = BOUNDS["noise_floor"].low

#: Largest relative hyperparameter (``regularizer``, ``noise_scale``, ``ridge``).
MAX_RELATIVE = BOUNDS["noise_scale"].high

#: Smallest ``regularizer``. A robot dim's regulariser is at least this
#: fraction of its weights' variance, which keeps the robot covariance positive
#: definite in floating point (condition number ~1e9 at worst); a model file
#: whose robot regularisers fall below half of it is refused.
MIN_REGULARIZER = BOUNDS["regularizer"].low

#: Largest magnitude of any number in a model file (weights, regularisers,
#: noise): far above what a fit of values within ``MAX_ABS_VALUE`` makes, far
#: below where the likelihood's squares overflow.
MAX_MODEL_VALUE = 1e30

#: Model files (``.npz``): largest file, largest array member (uncompressed,
#: as its header and the archive declare it, checked before it is read),
#: largest metadata member, most archive members, most tasks.
MAX_MODEL_FILE_BYTES = 64 * 2**20
MAX_MEMBER_BYTES = 32 * 2**20
MAX_METADATA_BYTES = 2**20
MAX_MEMBERS = 1000
MAX_TASKS = 100
#: Speed-factor prior (:math:`\\sigma_\\alpha`, ``min_alpha_std``): a fit floors the
#: spread of its demos' durations at ``min_alpha_std``, at least this; finer is below
#: what sample timing can tell and makes the speed lattice needlessly fine.
MIN_ALPHA_STD = 1e-3
#: ... and at most this: durations spread ten times their mean are mis-stamped
#: or mislabelled demos. n demos of positive duration give less than
#: :math:`\\sqrt{n}` (all the time in one of them), so it takes over 100 to reach it.
MAX_ALPHA_STD = 10.0
#: Largest :math:`\\kappa = \\lambda_p/\\sigma_p^2` of a human dim (its weights'
#: regulariser over its observation noise): the likelihood factors
#: :math:`I + \\kappa\\Psi^T\\Psi` in floating point, which stays positive definite
#: while :math:`\\kappa\\|\\Psi^T\\Psi\\|` is far below 1e16. Fits with the default
#: options make 1e-4 to 1e-1; with ``regularizer=1e6`` and a noise floor of 1e-12, 4e7.
MAX_KAPPA = 1e9
#: Basis width h (phase units squared): the finest is 100 times below the
#: squared spacing of :data:`MAX_N_BASIS` bumps; a width near the smallest float
#: makes the basis NaN.
MIN_BASIS_WIDTH = 1e-6
#: Largest basis width h (phase units squared): far wider than the phase range, every
#: bump is flat.
MAX_BASIS_WIDTH = 1e6


def check_alpha_std(value, name: str = "min_alpha_std") -> float:
    """A speed-factor standard deviation within [MIN_ALPHA_STD, MAX_ALPHA_STD]."""
    return check_number(value, name, low=MIN_ALPHA_STD, high=MAX_ALPHA_STD)


def check_duration(times: ArrayLike, name: str = "times",
                   max_duration: float = MAX_DURATION_S) -> float:
    """Return the span of increasing ``times`` (s) after checking it is plausible.

    Parameters
    ----------
    times : array_like, shape (T,)
        Increasing finite sample times (s); already validated by ``check_times``.
    name : str
        Name used in error messages.
    max_duration : float
        Largest span accepted (s).

    Raises
    ------
    ValueError
        If the span exceeds ``max_duration`` or the median sample interval is
        below ``MIN_MEDIAN_DT_S``; the message says which unit the times look
        like (milliseconds, microseconds, nanoseconds).
    """
    t = np.asarray(times, dtype=np.float64)
    span = float(t[-1] - t[0]) if t.size else 0.0
    dt = float(np.median(np.diff(t))) if t.size > 1 else np.inf
    if span > max_duration:
        raise ValueError(
            f"{name}: expected at most {max_duration:g} s, got a span of {span:g} s"
            f"{_unit_hint(span, dt)}; raise max_duration= if this is really seconds"
        )
    if dt < MIN_MEDIAN_DT_S:
        raise ValueError(
            f"{name}: expected sample intervals of at least {MIN_MEDIAN_DT_S:g} s, got a median of "
            f"{dt:g} s{_unit_hint(span, dt)}"
        )
    return span


def _unit_hint(span: float, dt: float) -> str:
    """Say which unit ``times`` look like when read as seconds gives a human-scale motion."""
    for unit, factor in (("milliseconds", 1e3), ("microseconds", 1e6), ("nanoseconds", 1e9)):
        if 0.2 <= span / factor <= MAX_DURATION_S and (not np.isfinite(dt) or dt / factor >= 1e-4):
            return f" (looks like {unit}: divide by {factor:g})"
    if np.isfinite(dt) and dt > 1.0:
        return " (samples further apart than 1 s: absolute or unscaled timestamps?)"
    return ""


def check_time(t, name: str = "t", max_time: float = MAX_TIME_S) -> float:
    """Return ``t`` as a float after checking it is a finite time within ``max_time`` of 0 (s).

    Parameters
    ----------
    t : float
        Time since the motion started (s).
    name : str
        Name used in error messages.
    max_time : float
        Largest magnitude accepted (s).

    Raises
    ------
    ValueError
        If ``t`` is not a finite real number or ``|t| > max_time``; the message
        says when ``t`` looks like an absolute (clock) timestamp.
    """
    v = check_number(t, name)
    if abs(v) > max_time:
        hint = (" (looks like an absolute clock timestamp: pass the time since the motion "
                "started)" if abs(v) > 1e8 else "")
        raise ValueError(f"{name}: expected a time since the motion started of at most "
                         f"{max_time:g} s, got {v:g} s{hint}; raise max_time= if this is "
                         f"really seconds since the start")
    return v
