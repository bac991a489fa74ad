"""Every method on the same folds, preprocessing and stream (``python -m sandbox compare``).

For each method of :data:`~sandbox.methods.METHODS` and each fold, the models
are fitted on the same training trials (:func:`~sandbox.eval.loocv.prepare`'s
per-demo fits, :class:`~sandbox.methods.DemoLibrary`), and the held-out trial's
causal test stream is fed row by row to the method's predictor
(``observe(t, y)``): every predictor keeps the same samples (same
subsampling, validation and normalisation, :mod:`sandbox.core.stream`) and,
except ``static``, updates at the same rows (every ``window`` seconds). Each
trial is scored as the dynamic formulation of :mod:`sandbox.eval.loocv` is: the
executed (blended) command over the recording, e_p, e_q, e_phi, recognition at
the end and over the recording (at fractions of it), time-to-correct, and the
wall time of every update (the observe calls since the previous update,
filtering included).

Two splits:

* leave-one-out (default): every trial predicted by models of all tasks fitted
  on all other trials (multi-task recognition);
* ``holdout=n``: n trials per task drawn with ``seed``, each predicted by a
  model of its own task fitted on that task's other (not held-out) trials:
  the true task is given (intprim's protocol in issue 22).

``static`` observes ``ratio`` of the true duration and predicts once (the
paper's baseline); the others update every ``window`` s.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from sandbox.eval import metrics
from sandbox.eval.loocv import CURVE, EvalConfig, _score, prepare
from sandbox.eval.report import _section
from sandbox.eval.runner import map_trials

#: Fractions of the recording the table reports recognition at.
TABLE_FRACTIONS = (0.3, 0.5, 1.0)


@dataclass(frozen=True)
class CompareConfig:
    """What a comparison runs (all of it goes into ``compare.json``).

    Attributes
    ----------
    methods : names among :data:`~sandbox.methods.METHODS`.
    window : seconds between updates of every method but ``static``.
    ratio : observed fraction of ``static``.
    holdout : trials per task held out (0: leave-one-out).
    seed : seed of the held-out draw and of eBIP's random numbers.
    options : per-method predictor options, ``((method, ((name, value), ...)), ...)``.
    evaluation : model and predictor options shared by every method (``observe``,
        ``subsample``, blending...).
    """

    methods: tuple[str, ...]
    window: float = 0.2
    ratio: float = 0.5
    holdout: int = 0
    seed: int = 0
    options: tuple = ()
    evaluation: EvalConfig = field(default_factory=lambda: EvalConfig(windows=(0.2,)))

    def method_options(self, name: str) -> dict:
        """Options of method ``name``'s predictor (shared ones, then its own)."""
        ev = self.evaluation
        shared = {"subsample": ev.subsample, "blend_rate": ev.blend_rate,
                  "blend_delay": ev.blend_delay, "until_end": ev.until_end,
                  "end_prob": ev.end_prob}
        if name in ("dynamic", "static"):
            shared.update(likelihood=ev.likelihood, n_candidates=ev.n_candidates,
                          refine_steps=ev.refine_steps)
        if name == "ebip":
            shared["seed"] = self.seed
        return {**shared, **dict(dict(self.options).get(name, ()))}

    def to_dict(self) -> dict:
        """JSON-ready form (the evaluation's options as :meth:`EvalConfig.to_dict`)."""
        out = asdict(self)
        out["evaluation"] = self.evaluation.to_dict()
        return out


def splits(tasks: list[str], holdout: int, seed: int) -> list[tuple[int, tuple[int, ...]]]:
    """``(test trial, training trials)`` of every fold.

    Leave-one-out (``holdout=0``): each trial against all others. Otherwise
    ``holdout`` trials per task drawn with ``default_rng(seed)`` (in the order
    the tasks first appear), each against the other trials of its task.
    """
    n = len(tasks)
    if holdout == 0:
        return [(i, tuple(j for j in range(n) if j != i)) for i in range(n)]
    rng = np.random.default_rng(seed)
    out = []
    for task in dict.fromkeys(tasks):
        mine = [i for i, t in enumerate(tasks) if t == task]
        if len(mine) < holdout + 2:
            raise ValueError(f"holdout: expected at least {holdout + 2} trials of task "
                             f"{task!r} ({holdout} held out, 2 to fit), got {len(mine)}")
        held = sorted(rng.choice(mine, size=holdout, replace=False).tolist())
        rest = tuple(i for i in mine if i not in held)
        out += [(i, rest) for i in held]
    return out


def evaluate_method_trial(predictor, test, truth, model, fk, curve=CURVE,
                          goal_tol: float = 0.05) -> dict:
    """All measures of one held-out trial streamed through ``predictor`` (module docstring).

    ``truth`` is the trial preprocessed for training: its motion's end is the
    true duration T (as in :func:`~sandbox.eval.loocv.evaluate_trial`).
    """
    fk = metrics.goal_map(model, fk)          # task space: the positions themselves
    t = test.times - test.times[0]
    q = test.robot
    T = float(t[model.motion_end(t, q, truth.human)])
    goal = fk(q[-1])
    at, errors, believed, seconds = [], [], [], []
    spent = 0.0
    for ti, yi in zip(t, test.human):
        start = time.perf_counter()
        upd = predictor.observe(ti, yi)
        spent += time.perf_counter() - start
        if upd is None:
            continue
        seconds.append(spent)
        spent = 0.0
        at.append(upd.time / t[-1])
        errors.append(float(np.linalg.norm(fk(predictor.plan()[1][-1]) - goal)))
        believed.append(upd.task == test.task)       # the update's choice, as loocv
    res = _score(predictor.commands(t), q, goal, fk, abs(predictor.duration - T))
    res.update(task=test.task, source=test.source, duration=T,
               recognition=float(predictor.task == test.task),
               time_to_correct=metrics.time_to_correct(np.array(at), np.array(errors), goal_tol),
               n_updates=len(at), update_seconds=seconds)
    prior_ok = model.tasks[int(np.argmax(model.priors))] == test.task
    res["recognition_curve"] = believed_at(at, believed, curve, prior_ok)
    return res


def believed_at(at: list[float], believed: list[bool], curve, prior_ok: bool) -> list[float]:
    """1.0 where the task believed at each fraction of ``curve`` is right (the prior's
    before the first update), from the updates at fractions ``at`` of the recording."""
    out = []
    for c in curve:
        i = int(np.searchsorted(at, c + 1e-9, side="right"))
        out.append(float(believed[i - 1]) if i > 0 else float(prior_ok))
    return out


# ------------------------------------------------------------------ runner
_STATE: dict = {}


def _init(train, test, fits, folds, config: CompareConfig, method: str) -> None:
    _STATE.clear()
    _STATE.update(train=train, test=test, fits=fits, folds=folds, config=config, method=method)


def _run_one(i: int) -> dict:
    from sandbox.methods import DemoLibrary, make_predictor
    from sandbox.robot import BaxterKinematics

    train, test, fits, folds, config, method = (
        _STATE[k] for k in ("train", "test", "fits", "folds", "config", "method"))
    fk = _STATE.setdefault("fk", BaxterKinematics().fk)
    ti, rest = folds[i]
    mine = [fits[j] for j in rest]
    model = config.evaluation.model().fit_demo_fits(mine, train[0])    # trial ti unseen
    library = DemoLibrary.from_fits(model, mine)
    t = test[ti].times - test[ti].times[0]
    T = float(t[model.motion_end(t, test[ti].robot, train[ti].human)])
    predictor = make_predictor(method, library, dow_t=config.window, ratio=config.ratio,
                               expected_duration=T, **config.method_options(method))
    return evaluate_method_trial(predictor, test[ti], train[ti], model, fk,
                                 config.evaluation.curve, config.evaluation.goal_tol)


def prepare_all(train, test, config: CompareConfig, *, progress: bool = False):
    """The trials as the models see them and their per-demo fits, once for every method
    (:func:`~sandbox.eval.loocv.prepare`), and the folds (:func:`splits`)."""
    train, test, fits = prepare(train, test, config.evaluation, progress=progress)
    return train, test, fits, splits([d.task for d in train], config.holdout, config.seed)


def run_method(prepared, config: CompareConfig, method: str, *, workers: int = 1,
               progress: bool = False) -> tuple[list[dict], float]:
    """One method on every fold: the per-trial results and the wall time (s)."""
    train, test, fits, folds = prepared
    start = time.perf_counter()
    trials = map_trials(_run_one, len(folds), _init, (train, test, fits, folds, config, method),
                        workers=workers, progress=progress)
    return trials, time.perf_counter() - start


def method_row(trials: list[dict], n_boot: int = 1000) -> dict:
    """One method's row: macro means over tasks with 95 % bootstrap intervals (resampling
    trials within tasks) of e_p, e_q, e_phi, recognition (end), time-to-correct, the
    recognition at :data:`TABLE_FRACTIONS` of the recording and its late decay, the
    median e_p, and the median update time (s)."""
    tasks = list(dict.fromkeys(r["task"] for r in trials))
    keys = ("e_p", "e_q", "e_phi", "recognition", "time_to_correct", "nll", "coverage")
    row = _section(trials, tasks, lambda r: r, keys, n_boot)["mean"]
    groups = np.array([r["task"] for r in trials])
    curves = np.array([r["recognition_curve"] for r in trials])
    rec = metrics.curve_bootstrap(curves, groups, n_boot=n_boot)
    curve = [round(c, 6) for c in CURVE]
    for f in TABLE_FRACTIONS:
        j = curve.index(round(f, 6))
        row[f"recognition_{f:.1f}"] = float(curves[:, j].mean())
        row[f"recognition_{f:.1f}_ci"] = [rec["lo"][j], rec["hi"][j]]
    row["late_decay"], row["late_decay_ci"] = rec["decay"], rec["decay_ci"]
    row["recognition_curve"] = rec["mean"]
    row["recognition_curve_ci"] = [rec["lo"], rec["hi"]]
    e_p = np.array([r["e_p"] for r in trials])
    row["e_p_median"] = float(np.median(e_p))
    row["e_p_median_ci"] = list(metrics.bootstrap_ci(e_p, n_boot=n_boot,
                                                     statistic=lambda v, g: np.median(v)))
    seconds = np.array([s for r in trials for s in r["update_seconds"]])
    row["update_s_median"] = float(np.median(seconds)) if seconds.size else float("nan")
    row["update_s_median_ci"] = (list(metrics.bootstrap_ci(
        seconds, n_boot=n_boot, statistic=lambda v, g: np.median(v))) if seconds.size
        else [float("nan")] * 2)
    row["n_trials"] = len(trials)
    return row


def method_key(config: CompareConfig, method: str, token: str) -> str:
    """The key of a method's stored result: its options, the shared ones, the data, the version."""
    import hashlib

    import sandbox
    from sandbox.eval.evaluation import canonical

    body = {k: v for k, v in config.to_dict().items() if k not in ("methods", "options")}
    text = canonical({"method": method, "options": config.method_options(method),
                      "config": body, "data": token, "version": sandbox.__version__})
    return hashlib.sha256(text.encode()).hexdigest()[:32]


def stored(out: Path, method: str, key: str) -> dict | None:
    """The stored result of ``method`` in ``out/methods`` if its key is ``key``."""
    try:
        result = json.loads((out / "methods" / f"{method}.json").read_text())
    except (OSError, ValueError):
        return None
    return result if isinstance(result, dict) and result.get("key") == key else None


def run_compare(train, test, config: CompareConfig, out: str | Path, *, workers: int = 1,
                progress: bool = False, dataset: str = "",
                log: Callable[[str], None] = print) -> dict:
    """Every method of ``config`` (module docstring); writes ``out/methods/<method>.json`` as
    each finishes (a re-run skips those whose key matches) and returns the comparison
    (what :func:`write_outputs` writes)."""
    from sandbox.eval.evaluation import data_token, write_atomic
    from sandbox.eval.runner import one_blas_thread

    out = Path(out)
    token = data_token(train, test)
    prepared = None
    rows, runtimes = {}, {}
    for method in config.methods:
        key = method_key(config, method, token)
        result = stored(out, method, key)
        if result is None:
            if prepared is None:
                with one_blas_thread():
                    prepared = prepare_all(train, test, config, progress=progress)
            log(f"{method}: {len(prepared[3])} trials")
            trials, runtime = run_method(prepared, config, method, workers=workers,
                                         progress=progress)
            result = {"key": key, "method": method, "options": config.method_options(method),
                      "runtime_s": runtime, "row": method_row(trials), "trials": trials}
            write_atomic(out / "methods" / f"{method}.json", json.dumps(result))
        else:
            log(f"{method}: done before ({out / 'methods' / (method + '.json')})")
        rows[method], runtimes[method] = result["row"], result["runtime_s"]
    tasks = list(dict.fromkeys(d.task for d in train))
    n_trials = next(iter(rows.values()))["n_trials"] if rows else 0
    return {"dataset": dataset, "tasks": tasks, "n_trials": n_trials,
            "split": f"holdout {config.holdout} per task (true task given)" if config.holdout
            else "leave-one-out", "config": config.to_dict(), "curve": list(CURVE),
            "rows": rows, "runtime_s": runtimes}


COLUMNS = (("e_p", "e_p (m)", 3), ("e_p_median", "e_p median (m)", 3), ("e_q", "e_q (rad)", 3),
           ("e_phi", "e_φ (s)", 2), ("recognition_0.3", "recog. 30 %", 2),
           ("recognition_0.5", "recog. 50 %", 2), ("recognition_1.0", "recog. end", 2),
           ("late_decay", "late decay", 3), ("update_s_median", "update (ms)", 1))


def to_markdown(comparison: dict) -> str:
    """``compare.md``: one row per method, each cell ``mean [lo, hi]`` (95 %)."""
    lines = [f"# Methods compared on {comparison['dataset']}", "",
             f"{comparison['n_trials']} trials, {comparison['split']}; tasks "
             f"{', '.join(comparison['tasks'])}; observe "
             f"{','.join(comparison['config']['evaluation']['observe'] or ['all'])}; "
             f"update every {comparison['config']['window']:g} s (static: one update at "
             f"{comparison['config']['ratio']:g} of the motion). Macro means over tasks with "
             "95 % bootstrap intervals; update time: median wall time per update.", "",
             "| method | " + " | ".join(c[1] for c in COLUMNS) + " |",
             "|---" * (len(COLUMNS) + 1) + "|"]
    for method, row in comparison["rows"].items():
        cells = []
        for key, _, digits in COLUMNS:
            if row[key] is None:          # e_q of a task-space robot part
                cells.append("n/a")
                continue
            scale = 1000.0 if key == "update_s_median" else 1.0
            lo, hi = (np.array(row[f"{key}_ci"], dtype=float) * scale).tolist()
            cells.append(f"{row[key] * scale:.{digits}f} [{lo:.{digits}f}, {hi:.{digits}f}]")
        lines.append(f"| {method} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def write_outputs(comparison: dict, out: str | Path) -> list[Path]:
    """``compare.json``, ``compare.md`` and ``recognition.png`` in ``out``, each whole."""
    from sandbox.eval.evaluation import write_atomic
    from sandbox.eval.plots import plot_methods

    out = Path(out)
    figure = plot_methods(comparison, out / "recognition.png")
    write_atomic(out / "compare.json", json.dumps(comparison, indent=1))
    write_atomic(out / "compare.md", to_markdown(comparison))
    return [out / "compare.json", out / "compare.md", figure]
