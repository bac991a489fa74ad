"""Benchmark of one predictor update (the reference case of the core issue).

Reference case: 4 tasks (synthetic diverging left/right/up/down, 20 demos each,
as in the paper's experiments), P = 3, Q = 7, N = 31, 40 observations (the
first 2 s of a held-out motion at 100 Hz, 1 kept in 5), at least 50 speed
candidates per task, one BLAS thread (set ``OPENBLAS_NUM_THREADS=1`` before
starting Python; the command does). An update = phase estimation of every task
+ recognition + conditioning + blending over a 2 s robot horizon at 100 Hz.

Timed, from one run, as medians over ``repeats`` repetitions:

* ``update_ms``: :meth:`DynamicPredictor.update` as the online predictor runs
  it, with the likelihood's sufficient statistics grown as the 40 observations
  arrived (:mod:`sandbox.core.statistics`); ``observe_ms`` is what that growth
  costs per kept observation.
* ``familiarity_ms``: what the familiarity adds to that update
  (:mod:`sandbox.core.familiarity`): the six statistics of the update's
  prediction (:func:`~sandbox.core.familiarity.statistics`) and their ranking and
  combination against a calibration of the reference case's size (4
  tasks, the default time bins; its quantiles are drawn at random, as the cost
  does not depend on them). ``update_ms`` includes it only for a calibrated model,
  which the reference model is not. ``position_ms`` is the position statistic's
  share of it (:func:`~sandbox.core.evidence.position`, score ``"position"``/``"all"``).
* ``update_cold_ms``: the same update computing everything from the 40
  observations at update time (``incremental=False``).
* ``naive_update_ms``: the same update done the straightforward way, written
  here: a dense innovation covariance and its Cholesky per candidate and task,
  dense Kalman conditioning of the full weight vector, dense per-step covariances.
* ``update_multimodal_ms``: the same update with P = 17 observed dims (hand 3 +
  arm 6 + EMG 8, the recorded set's modalities), the 40 rows carrying all
  three. The arm and EMG of the reference demos are made up for timing only
  (:func:`_arm_and_emg`: an elbow and a shoulder offset from the hand, and
  task-dependent activity levels); their realism does not change the
  arithmetic. ``observe_multimodal_ms`` is the statistics' growth per row.
* ``roofline``: the reference update's flops, time and achieved GFLOP/s per stage, against
  this machine's batched 45 x 45 Cholesky and matrix-product rates measured in the same
  run (:mod:`sandbox.bench.roofline`).
* ``kernel``: which path factors the phase grid, ``"numba"`` (the optional compiled
  kernel, ``sandbox/core/_kernels.py``) or ``"numpy"``; with numba,
  ``update_numpy_ms`` is ``update_ms`` on the numpy path (``SANDBOX_KERNEL=numpy``).
* ``movement_primitives_condition_ms`` (if the package is installed): its ProMP
  over the same 10 dims conditioned by 40 sequential ``condition_position``
  calls, robot dims given a huge variance (it has no masked conditioning).
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable

import numpy as np

from sandbox.bench.roofline import roofline
from sandbox.core import DynamicPredictor, IProMP
from sandbox.core.blending import blend_unchecked, sigmoid_activations
from sandbox.core.interaction import condition, log_marginal_likelihood, observation_matrix
from sandbox.core.phase import Lattice, log_alpha_prior
from sandbox.core.recognition import task_posterior
from sandbox.limits import BOUNDS

TASKS = ("left", "right", "up", "down")
#: The longest window the predictors take (s): no automatic update within a bench stream,
#: the timed updates are called by hand.
NO_UPDATE_S = BOUNDS["dow_t"].high


def reference_case(seed: int = 0, n_per_task: int = 20, *, multimodal: bool = False,
                   with_demos: bool = False):
    """Fitted 4-task model, and the held-out motion's first 2 s at 100 Hz (times, human).

    ``multimodal``: the demos also carry ``arm`` and ``emg`` (P = 17, :func:`_arm_and_emg`).
    ``with_demos``: the training demos are returned too, last.
    """
    from sandbox.data.synthetic import make_dataset

    rng = np.random.default_rng(seed)
    demos = [d for d in make_dataset("diverging", n_per_task + 3, rng) if d.task in TASKS]
    if multimodal:
        demos = _arm_and_emg(demos, rng)
    train, test = [], None
    for task in TASKS:
        items = [d for d in demos if d.task == task]
        train += items[:n_per_task]
        if test is None and task == TASKS[0]:
            test = next(d for d in items[n_per_task:] if d.duration > 2.2)
    model = IProMP(n_basis=31).fit(train)
    t = test.times - test.times[0]
    keep = t < 2.0 - 1e-9
    if with_demos:
        return model, t[keep][:200], test.human[keep][:200], train
    return model, t[keep][:200], test.human[keep][:200]


def _arm_and_emg(demos, rng: np.random.Generator) -> list:
    """The demos with a made-up elbow, shoulder and task-dependent activity (for timing only)."""
    from sandbox.data.spec import ARM, EMG, HAND

    levels = dict(zip(TASKS, (150.0, 250.0, 350.0, 450.0)))
    out = []
    for d in demos:
        z = (d.times - d.times[0]) / d.duration
        elbow = d.human + np.array([0.25, 0.1, -0.1]) * (1 - 0.3 * z)[:, None]
        shoulder = np.array([1.4, 0.2, 0.35]) + 0.02 * np.sin(np.pi * z)[:, None]
        emg = levels[d.task] * (1 + 0.5 * np.sin(np.pi * z))[:, None] * np.linspace(0.5, 1.5, 8)
        emg = emg * (1 + 0.05 * rng.standard_normal(emg.shape))
        out.append(d.replace(human=np.hstack([d.human, elbow, shoulder, emg]), human_names=(),
                             modalities=(HAND, ARM, EMG)))
    return out


def _median_ms(fn: Callable[[], object], repeats: int) -> float:
    fn()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return 1e3 * float(np.median(times))


def _fed_predictor(model, times, values, **options) -> DynamicPredictor:
    pred = DynamicPredictor(model, dow_t=NO_UPDATE_S, horizon=2.0, **options)
    for t, y in zip(times, values):
        pred.observe(t, y)
    return pred


def _timed_update(pred: DynamicPredictor, t: float) -> Callable[[], object]:
    state = pred._plan                     # a Plan is never mutated: restoring is assigning

    def run():
        pred._plan = state
        pred.updates.clear()
        pred.ended = False             # an update that ends the motion holds the task after it
        return pred.update(t)

    return run


def naive_update(model, times, values, lattice: Lattice, horizon: float = 2.0, dt: float = 0.01):
    """The straightforward update: dense per-candidate Cholesky, dense conditioning."""
    P, Q, N = model.n_human, model.n_robot, model.basis.n_basis
    t_last = float(times[-1])
    durations, spans = lattice.durations, lattice.spans()
    noise = np.tile(np.r_[model.noise, np.ones(Q)], times.size)
    obs = np.hstack([values, np.full((times.size, Q), np.nan)]).ravel()
    best = []
    for k, task in enumerate(model.task_models):
        cov = task.weights.cov()
        scores = []
        for T in durations[spans[k, 0]:spans[k, 1]]:
            H = observation_matrix(model.basis, np.minimum(times / T, 1.0), P, Q)
            ll = log_marginal_likelihood(task.weights.mean, cov, H, obs, noise)
            lp = log_alpha_prior(np.array([T / task.nominal_duration]), task.alpha_mean,
                                 task.alpha_std)[0]
            scores.append((ll + lp, ll, T))
        best.append(max(scores))
    post = task_posterior(np.array([b[1] for b in best]), model.priors)
    k = int(np.argmax(post))
    task, T = model.task_models[k], best[k][2]
    mean, cov = condition(task.weights.mean, task.weights.cov(),
                          observation_matrix(model.basis, np.minimum(times / T, 1.0), P, Q),
                          obs, noise)
    steps = np.arange(t_last, t_last + horizon, dt)
    psi = model.basis(np.clip(steps / T, 0, 1))
    m_new = np.empty((steps.size, Q))
    c_new = np.empty((steps.size, Q, Q))
    for i, p in enumerate(psi):
        H = np.kron(np.eye(Q), p[None, :])
        m_new[i] = H @ mean[P * N:]
        c_new[i] = H @ cov[P * N:, P * N:] @ H.T
    fall, rise = sigmoid_activations(steps, t_last + 0.1, 50.0)
    return blend_unchecked(np.stack([m_new, m_new]), np.stack([c_new, c_new]),
                           np.stack([fall, rise]))


def movement_primitives_condition(model, times, values, repeats: int):
    """Median ms of 40 sequential ``condition_position`` calls of movement_primitives' ProMP."""
    try:
        from movement_primitives.promp import ProMP
    except ImportError:
        return None
    return _mp_time(ProMP, model, times, values, repeats)


def _mp_time(ProMP, model, times, values, repeats):
    from sandbox.data.synthetic import make_dataset

    demos = [d for d in make_dataset("diverging", 20, np.random.default_rng(1))
             if d.task == TASKS[0]]
    n = 100
    Ts = np.tile(np.linspace(0, 1, n), (len(demos), 1))
    Ys = np.array([np.hstack([d.resample(n).human, d.resample(n).robot]) for d in demos])
    promp = ProMP(n_dims=10, n_weights_per_dim=model.basis.n_basis)
    promp.imitate(Ts, Ys)
    T = float(np.mean([d.duration for d in demos]))
    cov = np.diag(np.r_[model.noise, np.full(7, 1e6)])

    def run():
        p = promp
        for t, y in zip(times, values):
            p = p.condition_position(np.r_[y, np.zeros(7)], y_cov=cov, t=min(t / T, 1.0))
        return p

    return _median_ms(run, repeats)


def run_core_benchmarks(repeats: int = 200, seed: int = 0) -> dict:
    """All core figures of the reference case in one dict (see the module docstring)."""
    model, t200, y200 = reference_case(seed)
    t_update = float(t200[::5][-1])
    n_cand = 50
    pred = _fed_predictor(model, t200, y200, n_candidates=n_cand)
    times, values = pred.observations()
    observe_ms = _observe_ms(model, t200, y200, n_cand)
    fast = _median_ms(_timed_update(pred, t_update), repeats)
    cold_pred = _fed_predictor(model, t200, y200, incremental=False, n_candidates=n_cand)
    cold = _median_ms(_timed_update(cold_pred, t_update), repeats)
    lattice = Lattice.for_tasks(model.task_models, n_cand, 3.0)
    naive_reps = min(repeats, max(20, repeats // 10))   # --repeats 1 means one
    naive = _median_ms(lambda: naive_update(model, times, values, lattice), naive_reps)
    upd = pred.update(t_update)
    spans = lattice.spans()
    familiarity_ms = _median_ms(_familiarity_run(model, pred, t_update), repeats)
    position_ms = _median_ms(_position_run(model, pred, t_update), repeats)
    out = {
        "update_ms": round(fast, 4),
        "familiarity_ms": round(familiarity_ms, 4),
        "position_ms": round(position_ms, 4),
        "update_cold_ms": round(cold, 4),
        "naive_update_ms": round(naive, 4),
        "speedup_vs_naive": round(naive / fast, 1),
        "speedup_cold_vs_naive": round(naive / cold, 1),
        "observe_ms": round(observe_ms, 4),
        "config": {
            "tasks": len(model.tasks), "P": model.n_human, "Q": model.n_robot,
            "N": model.basis.n_basis, "demos_per_task": 20,
            "observations": int(times.size), "observation_span_s": round(t_update, 3),
            "candidates_per_task": (spans[:, 1] - spans[:, 0]).tolist(),
            "lattice_n_candidates": n_cand,
            "candidates_note": "candidates over +/-3 sigma of each task's speed prior, at "
                               "least 50 per task (a candidate shorter than the observations "
                               "sees them past its end holding its final state)",
            "horizon_s": 2.0, "horizon_rate_hz": 100, "repeats": repeats,
            "naive_repeats": naive_reps, "recognised": upd.task,
        },
    }
    out.update(_kernel_figures(pred, t_update, repeats))
    out.update(_multimodal_figures(seed, repeats, n_cand, fast))
    out["roofline"] = roofline(_fed_predictor(model, t200, y200, n_candidates=n_cand), t_update,
                               repeats=max(repeats // 2, 1))
    mp = movement_primitives_condition(model, times, values, repeats)
    if mp is not None:
        out["movement_primitives_condition_ms"] = round(mp, 4)
        out["movement_primitives_note"] = (
            "movement_primitives ProMP (10 dims, N=31) conditioned by 40 sequential "
            "condition_position calls with variance 1e6 on the 7 robot dims (it has no masked "
            "conditioning); conditioning only: no phase estimation, recognition or blending")
    return out


def _kernel_figures(pred: DynamicPredictor, t: float, repeats: int) -> dict:
    """Which path factors the phase grid (``kernel``: "numba" when the optional compiled
    kernel is used, else "numpy") and, with the kernel, the update on the numpy path."""
    from sandbox.core import _kernels

    if _kernels.factor_kernel(pred.scorer.R + 1) is None:
        return {"kernel": "numpy"}
    before = os.environ.get(_kernels.ENV)
    os.environ[_kernels.ENV] = "numpy"
    try:
        numpy_ms = _median_ms(_timed_update(pred, t), repeats)
    finally:
        if before is None:
            del os.environ[_kernels.ENV]
        else:
            os.environ[_kernels.ENV] = before
    return {"kernel": "numba", "update_numpy_ms": round(numpy_ms, 4)}


def _multimodal_figures(seed: int, repeats: int, n_cand: int, hand_ms: float) -> dict:
    model, t200, y200 = reference_case(seed, multimodal=True)
    t_update = float(t200[::5][-1])
    pred = _fed_predictor(model, t200, y200, n_candidates=n_cand)
    ms = _median_ms(_timed_update(pred, t_update), repeats)
    return {"update_multimodal_ms": round(ms, 4),
            "multimodal_vs_hand": round(ms / hand_ms, 2),
            "observe_multimodal_ms": round(_observe_ms(model, t200, y200, n_cand), 4),
            "multimodal_config": {"P": model.n_human, "observe": list(model.modality_names),
                                  "recognised": pred.update(t_update).task}}


def _familiarity_run(model, pred: DynamicPredictor, t: float) -> Callable[[], object]:
    """One update's familiarity: the statistics of its prediction, ranked and combined."""
    from sandbox.core.calibration import EDGES, Calibration
    from sandbox.core.familiarity import COMPONENTS, chosen, statistics

    rng = np.random.default_rng(0)
    K, mean = len(model.tasks), float(model.task_models[0].mean_duration)
    records = [(np.arange(15) * 0.2, rng.lognormal(0.0, 1.0, (15, len(COMPONENTS))),
                rng.integers(0, K, 15)) for _ in range(80)]
    cal = Calibration.from_records(records, K, edges=np.array(EDGES) * mean)
    prediction = pred.last_prediction
    times, values = pred.observations()
    times, values = times[times <= t], values[times <= t]

    def run():
        value = statistics(model, prediction, t, times, values)
        return cal.familiarity(t, value, chosen(prediction))

    return run


def _position_run(model, pred: DynamicPredictor, t: float) -> Callable[[], object]:
    """One update's position statistic (:func:`~sandbox.core.evidence.position`)."""
    from sandbox.core.evidence import position
    from sandbox.core.familiarity import chosen

    prediction = pred.last_prediction
    times, values = pred.observations()
    times, values = times[times <= t], values[times <= t]
    k = chosen(prediction)
    return lambda: position(model, prediction, k, times, values)


def _observe_ms(model, times, values, n_candidates: int) -> float:
    """Median wall time of one kept observation (statistics growth included)."""
    pred = DynamicPredictor(model, dow_t=NO_UPDATE_S, subsample=1, n_candidates=n_candidates)
    samples = []
    for t, y in zip(times[::5], values[::5]):
        start = time.perf_counter()
        pred.observe(t, y)
        samples.append(time.perf_counter() - start)
    return 1e3 * float(np.median(samples))
