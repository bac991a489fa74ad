"""Leave-one-out cross-validation of the static and dynamic formulations (paper sec. 4).

Every trial is predicted by models of all tasks fitted on all other trials
(multi-task recognition); everything a model learns, the normaliser of
signal modalities included, comes from those other trials. Training demos use
the smoothing preprocessing, the test stream the causal one (only samples
received so far), as DESIGN.md asks. The models observe the modalities the
demonstrations carry (``EvalConfig.observe`` selects some of them). The true
duration of a trial is its motion's (:func:`~sandbox.core.model.motion_end`,
the same rule the models are fitted with); recognition over time is reported
at fractions of the whole recording, idle tail included.
For each trial this module computes, on the same kept observations
(valid samples of each modality, 1 kept in ``subsample``):

* the oracle: all observations, the true task at the true duration;
* the static formulation at each observed ratio f of the true duration (one
  prediction, evaluated over the whole motion, as the paper does);
* the dynamic formulation at each window dow_t (the executed, blended command).
"""

from __future__ import annotations

import copy
import time
from dataclasses import asdict, dataclass, field

import numpy as np

from sandbox.core import DynamicPredictor, IProMP, familiarity, predict
from sandbox.core.inference import conditioned_robot, held_trajectory
from sandbox.core.jitter import JITTER_FACTOR
from sandbox.core.model import SIGNAL_FLOOR
from sandbox.core.phase import Lattice
from sandbox.core.statistics import StreamStatistics
from sandbox.core.stream import ObservationStream
from sandbox.eval import metrics
from sandbox.eval.progress import bar
from sandbox.eval.runner import map_trials, one_blas_thread

RATIOS = tuple(round(0.1 * i, 1) for i in range(1, 10))
WINDOWS = (1.0, 0.5, 0.2, 0.1)
CURVE = tuple(round(0.1 * i, 1) for i in range(1, 11))


@dataclass(frozen=True)
class EvalConfig:
    """What an evaluation runs (all of it goes into ``report.json``).

    Attributes
    ----------
    ratios : observed fractions of the static formulation.
    windows : dynamic observation windows dow_t (s).
    subsample : keep 1 of this many valid tracker frames (~30 Hz -> ~15 Hz).
    likelihood, window_mode, n_candidates, refine_steps, blend_rate, blend_delay, until_end,
    end_prob :
        predictor options (:class:`~sandbox.core.DynamicPredictor`).
    n_basis, regularizer, span_reg, post_end, noise_scale, noise_floor, condition_floor,
    signal_floor, noise_floors, jitter_floor, shrinkage, settle_tol, arrive_tol, robot_tol :
        model options (:class:`~sandbox.core.IProMP`).
    observe : modalities the models observe (None: all the demonstrations carry).
    goal_tol : distance (m) for time-to-correct.
    curve : fractions of the motion at which recognition over time is reported.
    """

    ratios: tuple[float, ...] = RATIOS
    windows: tuple[float, ...] = WINDOWS
    subsample: int = 2
    likelihood: str = "joint"
    window_mode: str = "all"
    n_candidates: int = 50
    refine_steps: int = 1
    blend_rate: float = 50.0
    blend_delay: float = 0.1
    until_end: bool = True
    end_prob: float = 0.5
    n_basis: int = 21
    regularizer: float = 1e-3
    span_reg: float | str | None = None
    post_end: float | None = None
    noise_scale: float = 1.0
    noise_floor: float | str = 0.02
    condition_floor: float | str | None = None
    signal_floor: float = SIGNAL_FLOOR
    noise_floors: tuple[tuple[str, float], ...] = ()
    jitter_floor: float | None = JITTER_FACTOR
    shrinkage: str = "none"
    settle_tol: float | None = 0.05
    arrive_tol: float | None = 0.02
    robot_tol: float | None = 0.01
    observe: tuple[str, ...] | None = None
    goal_tol: float = 0.05
    curve: tuple[float, ...] = field(default=CURVE)

    def model(self) -> IProMP:
        """An unfitted model with these options."""
        return IProMP(n_basis=self.n_basis, regularizer=self.regularizer, span_reg=self.span_reg,
                      post_end=self.post_end, noise_scale=self.noise_scale,
                      noise_floor=self.noise_floor, condition_floor=self.condition_floor,
                      signal_floor=self.signal_floor, noise_floors=dict(self.noise_floors),
                      jitter_floor=self.jitter_floor, shrinkage=self.shrinkage,
                      settle_tol=self.settle_tol, arrive_tol=self.arrive_tol,
                      robot_tol=self.robot_tol)

    def predictor_options(self) -> dict:
        """The keyword arguments of the predictors these settings make."""
        return {"subsample": self.subsample, "likelihood": self.likelihood,
                "n_candidates": self.n_candidates, "refine_steps": self.refine_steps,
                "blend_rate": self.blend_rate, "blend_delay": self.blend_delay,
                "until_end": self.until_end, "end_prob": self.end_prob}

    def to_dict(self) -> dict:
        """Every setting by name (JSON-ready: a report's ``config``)."""
        return asdict(self)


def kept_observations(model, times, human, subsample: int, *, like=None):
    """Observations a predictor keeps of this stream: times (s,), values (s, P) (NaN: not kept).

    ``like`` is an :class:`~sandbox.core.stream.ObservationStream` of ``model`` with
    this ``subsample`` (e.g. a predictor's ``stream``): a reset copy of it is fed instead
    of a new one, which saves computing the model's bounds again. It is left unchanged.
    """
    if like is None:
        stream = ObservationStream(model, subsample=subsample)
    else:
        if like.subsample != subsample:
            raise ValueError(f"like: expected a stream with subsample={subsample}, got "
                             f"{like.subsample}")
        stream = copy.copy(like)
        stream.reset()                   # its own buffers: ``like`` keeps its observations
    for ti, yi in zip(times, human):
        stream.accept(ti, yi)
    return stream.observations()


def evaluate_trial(model: IProMP, test, config: EvalConfig, fk, truth=None) -> dict:
    """All measures of one held-out trial (see the module docstring).

    ``truth`` is the same trial preprocessed for training (smoothed; default
    ``test``): its motion's end is the true duration. ``fk`` maps joints (..., Q) to the
    gripper position (..., 3) (m); a model whose robot part is in task space is scored on
    its positions instead (:func:`~sandbox.eval.metrics.goal_map`; e_q None).
    """
    truth = test if truth is None else truth
    fk = metrics.goal_map(model, fk)
    t = test.times - test.times[0]
    q = test.robot
    T = float(t[model.motion_end(t, q, truth.human)])
    k = model.task_index(test.task)
    goal = fk(q[-1])
    # one predictor built per trial: every window's is its copy (with_window), sharing its
    # Scorer, prior plan and bounds, which depend only on the model
    template = DynamicPredictor(model, dow_t=WINDOWS[0], window=config.window_mode,
                                incremental=False, **config.predictor_options())
    scorer = template.scorer
    t_obs, y_obs = kept_observations(model, t, test.human, config.subsample,
                                     like=template.stream)
    opts = dict(likelihood=config.likelihood, n_candidates=config.n_candidates,
                refine_steps=config.refine_steps)
    oracle = conditioned_robot(model, scorer, t_obs, y_obs, k, T)   # no phase estimate
    windows = {w: update_times(t, t_obs, w) for w in config.windows}
    cuts = {f: f * T for f in config.ratios}
    shared = set(cuts.values())
    if config.window_mode == "all":
        shared |= {x for times in windows.values() for x in times}
    preds = predictions_at(model, scorer, t_obs, y_obs, sorted(shared), config, opts)
    static = [preds[cut] for cut in cuts.values()]
    scores = _scores([held_trajectory(oracle, T, model.basis, t)]
                     + [pred.trajectory(model.basis, t) for pred in static],
                     [0.0] + [abs(pred.duration - T) for pred in static], q, goal, fk)
    out = {"task": test.task, "source": test.source, "duration": T, "oracle": scores[0],
           "static": {}}
    for f, pred, res in zip(cuts, static, scores[1:]):
        res["recognition"] = float(pred.task_index == k)
        out["static"][f"{f:.1f}"] = res
    out["dynamic"] = {f"{w:.1f}": _dynamic(template.with_window(w), test, t, q, T, goal, fk,
                                           config, windows[w], preds, t_obs)
                      for w in config.windows}
    out["recording"] = float(t[-1])
    return out


def update_times(t, t_obs, window: float) -> list[float]:
    """Row times at which a :class:`DynamicPredictor` fed this stream updates."""
    return familiarity.update_times(t, t_obs, window).tolist()


def predictions_at(model, scorer, t_obs, y_obs, times, config, opts) -> dict:
    """:func:`~sandbox.core.predict` from the observations up to each time (sorted times).

    A prediction depends on the observations only, not on the time asked: times with the
    same kept observations share one (the same object), made once. On the recorded set
    a fifth of the times repeat an earlier one's observations, mostly the static ratios'
    cut times against the windows' update times.
    """
    stats = None
    if config.likelihood == "joint":
        stats = StreamStatistics(scorer, Lattice.for_tasks(model.task_models,
                                                           config.n_candidates))
    out, made, fed = {}, {}, 0
    for tau in times:
        n = int(np.searchsorted(t_obs, tau, side="right"))
        if n not in made:
            if stats is not None:
                for j in range(fed, n):
                    stats.add(t_obs[j], y_obs[j])
                fed = n
            made[n] = predict(model, scorer, t_obs[:n], y_obs[:n], stats=stats, **opts)
        out[tau] = made[n]
    return out


def _score(traj, q, goal, fk, e_phi) -> dict:
    return _scores([traj], [e_phi], q, goal, fk)[0]


def _scores(trajs, e_phis, q, goal, fk) -> list[dict]:
    """The measures of predicted trajectories (means (T, Q), covariances (T, Q, Q)), their
    final means' goals in one ``fk`` call (the same numbers as one call each)."""
    ends = fk(np.array([mean[-1] for mean, _ in trajs]))
    out = []
    for (mean, cov), end, e_phi in zip(trajs, ends, e_phis):
        e_q = None if fk is metrics.task_goal else metrics.joint_rms(mean, q)   # n/a in task space
        nll, coverage = metrics.calibration(q, mean, cov)
        out.append({"e_p": float(np.linalg.norm(end - goal)), "e_q": e_q,
                    "e_phi": float(e_phi), "nll": nll, "coverage": coverage})
    return out


def _dynamic(pred, test, t, q, T, goal, fk, config, times, preds, t_obs) -> dict:
    model = pred.model
    ends, believed, at_recording = [], [], []

    def record(upd):
        at_recording.append(upd.time / t[-1])
        ends.append(pred.plan()[1][-1])      # the plan's last command; its fk after the loop
        believed.append(upd.task == test.task)

    if config.window_mode == "all":        # the same estimates a streamed predictor makes
        for tau in times:
            upd = pred.apply(tau, preds[tau],
                             n_observations=int(np.searchsorted(t_obs, tau, side="right")))
            if upd is not None:
                record(upd)
    else:
        for ti, yi in zip(t, test.human):
            upd = pred.observe(ti, yi)
            if upd is not None:
                record(upd)
    res = _score(pred.commands(t), q, goal, fk, abs(pred.duration - T))
    res["recognition"] = float(pred.task == test.task)
    # fk of all the updates' last commands in one call (the same numbers as one call each)
    goal_err = [float(np.linalg.norm(p - goal)) for p in fk(np.array(ends))] if ends else []
    res["time_to_correct"] = metrics.time_to_correct(np.array(at_recording), np.array(goal_err),
                                                     config.goal_tol)
    res["jumps"] = [u.jump for u in pred.updates]
    prior_ok = model.tasks[int(np.argmax(model.priors))] == test.task
    curve = []
    for c in config.curve:
        i = int(np.searchsorted(at_recording, c + 1e-9, side="right"))
        curve.append(float(believed[i - 1]) if i > 0 else float(prior_ok))
    res["recognition_curve"] = curve
    res["n_updates"] = len(pred.updates)
    return res


# ------------------------------------------------------------------ runner
_STATE: dict = {}


def _init(train, test, fits, config) -> None:
    _STATE.update(train=train, test=test, fits=fits, config=config)


def prepare(train, test, config: EvalConfig, *, progress: bool = False) -> tuple[list, list, list]:
    """The trials as the models see them (``config.observe`` selected) and each one's fit.

    Returns ``(train, test, fits)``, ``fits[i]`` the
    :meth:`~sandbox.core.IProMP.demo_fit` of ``train[i]`` that :func:`fold` combines.
    ``progress`` draws a bar of the fits on stderr.
    """
    if config.observe is not None:
        train = [d.select(config.observe) for d in train]
        test = [d.select(config.observe) for d in test]
    model, fits = config.model(), []
    with bar(len(train), "fitting", progress, unit="demo") as shown:
        for d in train:
            fits.append(model.demo_fit(d))
            shown.update()
    return list(train), list(test), fits


def fold(train, test, fits, config: EvalConfig, i: int, fk) -> dict:
    """Fold ``i`` of the leave-one-out: trial ``i`` predicted by models fitted on all others.

    ``train, test, fits`` come from :func:`prepare`; ``fk`` maps joints to the
    gripper position (:meth:`~sandbox.robot.BaxterKinematics.fk`).
    """
    model = config.model().fit_demo_fits(fits[:i] + fits[i + 1:], train[0])   # trial i unseen
    return evaluate_trial(model, test[i], config, fk, train[i])


def _run_one(i: int) -> dict:
    from sandbox.robot import BaxterKinematics

    train, test, fits, config = (_STATE[k] for k in ("train", "test", "fits", "config"))
    fk = _STATE.setdefault("fk", BaxterKinematics().fk)
    return fold(train, test, fits, config, i, fk)


def run_loocv(train, test, config: EvalConfig, *, workers: int = 1,
              progress: bool = False) -> tuple[list[dict], float]:
    """Leave-one-out over all trials. Returns the per-trial results and the wall time (s).

    Parameters
    ----------
    train, test : sequence of Demonstration
        The same trials, preprocessed for training (smoothed) and as test streams
        (causal); ``train[i]`` and ``test[i]`` must be the same trial.
    config : EvalConfig
    workers : int
        Processes (fork); 1 runs in this process.
    progress : bool
        Show progress bars (fitting, then trials) on stderr.
    """
    if len(train) != len(test) or any(a.source != b.source or a.task != b.task
                                      for a, b in zip(train, test)):
        raise ValueError("train and test: expected the same trials in the same order")
    start = time.perf_counter()
    with one_blas_thread():
        results = _run_all(train, test, config, workers, progress)
    return results, time.perf_counter() - start


def _run_all(train, test, config: EvalConfig, workers: int, progress: bool) -> list[dict]:
    train, test, fits = prepare(train, test, config, progress=progress)
    return map_trials(_run_one, len(test), _init, (train, test, fits, config),
                      workers=workers, progress=progress, cost=trial_costs(test))


def trial_costs(trials) -> list[float]:
    """Each trial's duration (s): a fold's work grows with its updates, so with it."""
    return [d.duration for d in trials]
