"""Test-only evaluation: every trial of a set predicted by one given, already fitted model.

``python -m sandbox evaluate --model model.npz`` runs this instead of the
leave-one-out (:mod:`sandbox.eval.loocv`): no model is refitted, so the
trials should be ones the model was not fitted on (another recording, another
seed of a synthetic set); otherwise the figures are in-sample. Each trial is
measured exactly as one fold of the leave-one-out measures it
(:func:`~sandbox.eval.loocv.evaluate_trial`: oracle, static at each ratio,
dynamic at each window), so the report has the same sections, and its
``config`` says ``mode: test-only`` with the model's file and its own options.
"""

from __future__ import annotations

import time
from dataclasses import replace

from sandbox.eval.loocv import EvalConfig, evaluate_trial, trial_costs
from sandbox.eval.runner import map_trials

#: The value of ``report["config"]["mode"]`` of a test-only evaluation.
MODE = "test-only"
#: Options of a fitted model that :class:`EvalConfig` also names (copied into the report).
MODEL_OPTIONS = ("regularizer", "noise_scale", "noise_floor", "condition_floor",
                 "signal_floor", "jitter_floor", "shrinkage", "settle_tol", "arrive_tol")

_STATE: dict = {}


def check_compatible(model, test) -> None:
    """Raise ``ValueError`` unless ``model`` can predict every trial of ``test``.

    The trials must carry the model's modalities in its order, the model must
    know each trial's task, and the robot dims must agree (count and names).
    """
    names = tuple(model.modality_names)
    for demo in test:
        carried = tuple(m.name for m in demo.modalities)
        if carried != names:
            raise ValueError(f"--model: the model observes {','.join(names)}; the trial "
                             f"{demo.source} carries {','.join(carried)}")
    unknown = sorted({d.task for d in test} - set(model.tasks))
    if unknown:
        raise ValueError(f"--model: the data has tasks {unknown} the model does not know "
                         f"(it knows {list(model.tasks)}); choose some with --tasks")
    for demo in test:
        robot = tuple(getattr(demo, "robot_names", ()) or ())
        if demo.robot.shape[1] != model.n_robot or (robot and model.robot_names
                                                    and robot != tuple(model.robot_names)):
            raise ValueError(f"--model: the model drives {model.n_robot} robot dims "
                             f"{list(model.robot_names)}; the trial {demo.source} has "
                             f"{demo.robot.shape[1]} {list(robot)}")


def model_config(model, config: EvalConfig) -> EvalConfig:
    """``config`` with the options the model was fitted with (its basis size, floors, ...)."""
    options = {k: getattr(model, k) for k in MODEL_OPTIONS}
    options["noise_floors"] = tuple(sorted(model.noise_floors.items()))
    return replace(config, n_basis=model.basis.n_basis, **options)


def describe(model, config: EvalConfig, path: str) -> dict:
    """The report's ``config`` of a test-only run: the options, ``mode`` and the model."""
    return {**model_config(model, config).to_dict(), "mode": MODE, "model": str(path),
            "model_tasks": list(model.tasks)}


def _init(model, train, test, config) -> None:
    _STATE.clear()
    _STATE.update(model=model, train=train, test=test, config=config)


def _run_one(i: int) -> dict:
    from sandbox.robot import BaxterKinematics

    fk = _STATE.setdefault("fk", BaxterKinematics().fk)
    return evaluate_trial(_STATE["model"], _STATE["test"][i], _STATE["config"], fk,
                          _STATE["train"][i])


def run_heldout(model, train, test, config: EvalConfig, *, workers: int = 1,
                progress: bool = False) -> tuple[list[dict], float]:
    """Predict every trial with ``model``. Returns the per-trial results and the wall time (s).

    Parameters
    ----------
    model : IProMP
        A fitted model (e.g. :meth:`~sandbox.core.IProMP.load`); never refitted.
    train, test : sequence of Demonstration
        The same trials preprocessed for training (smoothed: their motion's end
        is the true duration) and as test streams (causal); ``train[i]`` and
        ``test[i]`` must be the same trial, with the model's modalities.
    config : EvalConfig
        Ratios, windows and predictor options (its model options are unused).
    workers : int
        Processes (fork); 1 runs in this process.
    progress : bool
        Show a progress bar on stderr.
    """
    if len(train) != len(test) or any(a.source != b.source or a.task != b.task
                                      for a, b in zip(train, test)):
        raise ValueError("train and test: expected the same trials in the same order")
    check_compatible(model, test)
    start = time.perf_counter()
    results = map_trials(_run_one, len(test), _init, (model, list(train), list(test), config),
                         workers=workers, progress=progress, cost=trial_costs(test))
    return results, time.perf_counter() - start


def per_trial(trials: list[dict]) -> list[dict]:
    """What each trial's predictions scored: file, task, goal error and recognition of the
    static formulation at each ratio and the dynamic one at each window."""
    def brief(entry: dict) -> dict:
        return {"e_p": entry["e_p"], "e_phi": entry["e_phi"],
                "recognition": entry["recognition"]}

    return [{"source": r["source"], "task": r["task"], "duration": r["duration"],
             "static": {f: brief(e) for f, e in r["static"].items()},
             "dynamic": {w: brief(e) for w, e in r["dynamic"].items()}} for r in trials]
