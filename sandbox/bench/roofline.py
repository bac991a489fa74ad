"""Roofline of one predictor update: its arithmetic per stage against this machine's kernels.

One update (:meth:`~sandbox.core.updating.PredictorBase.update`) has four stages:

* ``phase``: the speed candidates of every task (:func:`~sandbox.core.phase.estimate_phase`:
  the grid's log-likelihoods from the augmented r x r factors, eq. 11-13 (with the compiled
  kernels the stream keeps the factors up to date as observations arrive, so the grid reads
  their pivots; on the numpy path it factors them), and the
  parabolic refinement, which builds the likelihood's statistics of a few new
  (duration, task) pairs from the observations);
* ``recognition``: the task posterior (eq. 14-15) and the rest hypothesis
  (:mod:`sandbox.core.rest`);
* ``conditioning``: the robot weights of the chosen task (eq. 8,
  :func:`~sandbox.core.factor.condition_robot`);
* ``blending``: the new robot distribution on the plan's knots and its product with the
  executed plan (eq. 4, 16-18, :meth:`~sandbox.core.plan.Plan.blended`).

:func:`update_flops` counts each stage's floating-point operations analytically, as the
implementation executes them: a dense product of (m x k) by (k x n) is 2mkn, a Cholesky
factor of n x n is n^3/3, a triangular inverse n^3/3, a triangular solve with k right-hand
sides n^2 k, an LU solve (2/3)n^3 + 2n^2 k; elementwise work counts one per entry and
operation (an exponential as one). :func:`machine_rates` measures, in the same run, the
rate this machine's numpy and LAPACK reach on a batch of 45 x 45 Cholesky factors (the
kernel of the phase stage, one matrix per LAPACK call) and on a 512 x 512 matrix product
(close to one core's peak). :func:`roofline` times each stage alone (medians) and reports
its achieved GFLOP/s and that as a fraction of both rates: a stage far below the
Cholesky rate is bound by numpy calls, not by arithmetic.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from sandbox.core import _kernels
from sandbox.core.factor import condition_robot
from sandbox.core.pairstats import pair_kernel
from sandbox.core.phase import estimate_phase
from sandbox.core.plan import Held
from sandbox.core.recognition import task_posterior
from sandbox.core.rest import motion_probability, rest_log_likelihood

#: Stages of one update, in the order an update runs them.
STAGES = ("phase", "recognition", "conditioning", "blending")


def _median_s(fn: Callable[[], object], repeats: int) -> float:
    fn()
    times = []
    for _ in range(max(int(repeats), 1)):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def machine_rates(repeats: int = 20, batch: int = 256, n: int = 45) -> dict:
    """This machine's GFLOP/s on batched n x n Cholesky factors and a 512 x 512 product.

    Parameters
    ----------
    repeats : int
        Timed repetitions (medians).
    batch, n : int
        ``batch`` symmetric positive definite n x n matrices factored by one
        ``numpy.linalg.cholesky`` call (n^3/3 flops each).

    Returns
    -------
    dict
        ``cholesky45_gflops``, ``matmul_gflops`` (one 512 x 512 x 512 product, 2 * 512^3 flops).
    """
    rng = np.random.default_rng(0)
    x = rng.standard_normal((batch, n, n))
    spd = x @ x.transpose(0, 2, 1) + n * np.eye(n)
    chol = _median_s(lambda: np.linalg.cholesky(spd), repeats)
    a, b = rng.standard_normal((2, 512, 512))
    mm = _median_s(lambda: a @ b, repeats)
    return {f"cholesky{n}_gflops": round(batch * n**3 / 3 / chol / 1e9, 3),
            "matmul_gflops": round(2 * 512**3 / mm / 1e9, 3)}


def update_flops(pred, t: float) -> dict:
    """Floating-point operations of one update of ``pred`` at ``t`` (s), per stage.

    Parameters
    ----------
    pred : PredictorBase
        A predictor fed with observations, joint likelihood, incremental statistics
        (the update's grid reads them; their growth is :meth:`observe`'s work). With the
        compiled kernels the stream keeps every pair's factor, so the grid counts only
        their log pivots; on the numpy path it counts the factorisations.
    t : float
        Update time (s).

    Returns
    -------
    dict
        One count per :data:`STAGES` (flops).
    """
    sc, model = pred.scorer, pred.model
    times, values = pred._window(t)
    s, K, N, R1 = times.size, sc.K, sc.N, sc.R + 1
    spans = pred._lattice.spans()
    M = int((spans[:, 1] - spans[:, 0]).sum())
    if _kernels.factor_kernel(R1) is None:                       # numpy: the grid factors
        phase = M * (R1**3 / 3 + 4 * R1) + M * 12                # factor_scores, prior
    else:                                                        # kept factors: log pivots
        phase = M * (2 * R1) + M * 12                            # summed, prior
    phase += pred.refine_steps * _pair_flops(sc, values, K, s)   # one new pair per task
    P = values.shape[1]
    recognition = 8 * s * P + 30 * K
    r, Q = sc.rank[0], model.n_robot
    conditioning = r * r + r * r * N * Q + 2 * N * Q * r
    return {"phase": phase, "recognition": recognition, "conditioning": conditioning,
            "blending": _blend_flops(pred, t, N, Q, r)}


def _pair_flops(sc, values, M: int, s: int) -> float:
    """Flops of the likelihood of M new (duration, task) pairs from s observations."""
    N, R1 = sc.N, sc.R + 1
    present = sc.present(values)
    flops = M * s * N * 6                                        # basis at t/T
    rows_space = pair_kernel(R1) is not None     # the kernel's rows' space when sg < N
    for g in sc.groups:
        sg, pg = int(present[g.modality].sum()), g.dims.size
        flops += M * (2 * sg * N * N + 2 * sg * N * pg)          # G = Psi^T Psi, beta
        if rows_space and sg < N:                                # pairstats' F, X = F V
            flops += M * (2 * N**3 / 3 + 4 * N * N * pg + 3 * sg * sg * N + sg**3 / 3)
            flops += M * (2 * sg * N * pg * R1 + 2 * sg * pg * R1 * R1 + 2 * N * pg * R1)
            continue
        flops += M * (2 * N**3 / 3 + 4 * N**3 + 4 * N * N * pg)  # b_part: chol, trtri, Q, W
        flops += M * (2 * N * N * pg * R1 + 2 * N * pg * R1 * R1 + 2 * N * pg * R1)
    return flops + M * (R1**3 / 3 + 4 * R1)


def _blend_flops(pred, t: float, N: int, Q: int, r: int) -> float:
    """Flops of the new distribution on the plan's knots and its product with the plan."""
    how, prediction = pred._blending, pred.last_prediction
    plan = _prior_plan(pred).blended(t, lambda ts: prediction.trajectory(pred.model.basis, ts),
                                     prediction.duration, how)[0]
    knots = plan.times[plan.times > t]
    steps = knots.size
    # computed steps: up to the predicted end, then held (Prediction.trajectory)
    moving = min(int(np.count_nonzero(knots < prediction.duration)) + 1, steps)
    # knots blended: until the falling sigmoid is below 1e-12 (plan._blend)
    blended = min(steps, int((how.delay + np.log(1e12) / how.rate) / how.dt) + 1)
    trajectory = moving * (6 * N + 2 * N * Q + 2 * N * Q * r + 2 * Q * Q * r + 2 * N + Q)
    interpolate = blended * 4 * (Q * Q + Q)
    product = blended * (2 * Q**3 / 3 + 2 * Q * Q * (Q + 2) + 2 * Q**3 + 6 * Q * Q)
    return trajectory + interpolate + product


def _stage_runs(pred, t: float) -> dict:
    """One callable per stage doing that stage's work of an update at ``t`` alone."""
    model, sc = pred.model, pred.scorer
    times, values = pred._window(t)
    stats = pred._stats if pred._stats is not None and pred._stats.count == times.size else None
    est = estimate_phase(sc, model.task_models, times, values, n_candidates=pred.n_candidates,
                         width=pred.width, refine_steps=pred.refine_steps, stats=stats)
    pred.updates.clear()
    pred.ended = False
    pred._plan = _prior_plan(pred)
    upd = pred.update(t)
    k = model.task_index(upd.task)
    prediction = pred.last_prediction
    before = _prior_plan(pred)

    def recognition():
        post = task_posterior(est.log_likelihood, model.priors)
        still = rest_log_likelihood(values, sc.sigma2, sc.start_mean, sc.start_var)
        return post, motion_probability(est.log_likelihood, model.priors, still)

    return {
        "phase": lambda: estimate_phase(sc, model.task_models, times, values,
                                        n_candidates=pred.n_candidates, width=pred.width,
                                        refine_steps=pred.refine_steps, stats=stats),
        "recognition": recognition,
        "conditioning": lambda: condition_robot(model.task_models[k].weights, est.factors[k],
                                                model.n_human, sc.rank[k]),
        "blending": lambda: before.blended(t, Held(prediction.robot, prediction.duration,
                                                   model.basis),   # as an update: fused
                                           prediction.duration, pred._blending),
    }


def _prior_plan(pred):
    """The plan before any update (the prior mixture)."""
    from sandbox.core.plan import Plan

    return Plan.prior(pred.model, pred.dt)


def roofline(pred, t: float, repeats: int = 100, rates: dict | None = None) -> dict:
    """Flops, time and achieved rate of each stage of one update of ``pred`` at ``t``.

    Parameters
    ----------
    pred : PredictorBase
        Fed with the observations (joint likelihood, incremental statistics).
    t : float
        Update time (s).
    repeats : int
        Timed repetitions per stage (medians).
    rates : dict, optional
        :func:`machine_rates` of this run (measured here if not given).

    Returns
    -------
    dict
        ``stages``: per stage ``mflop``, ``ms``, ``gflops``, ``of_cholesky45`` and
        ``of_matmul`` (fractions of the machine's rates); ``total`` likewise over the
        stages; the machine's rates.
    """
    rates = machine_rates() if rates is None else rates
    runs = _stage_runs(pred, t)
    flops = update_flops(pred, t)
    chol, mm = rates["cholesky45_gflops"], rates["matmul_gflops"]
    out, total_f, total_s = {}, 0.0, 0.0
    for name in STAGES:
        sec = _median_s(runs[name], repeats)
        total_f, total_s = total_f + flops[name], total_s + sec
        out[name] = _row(flops[name], sec, chol, mm)
    return {"stages": out, "total": _row(total_f, total_s, chol, mm), **rates}


def _row(flops: float, sec: float, chol: float, mm: float) -> dict:
    gflops = flops / sec / 1e9
    return {"mflop": round(flops / 1e6, 4), "ms": round(1e3 * sec, 4),
            "gflops": round(gflops, 3), "of_cholesky45": round(gflops / chol, 3),
            "of_matmul": round(gflops / mm, 4)}
