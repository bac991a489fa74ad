"""Familiarity records of normal and out-of-distribution motions, for ``python -m sandbox ood``.

Two ways to get a model, the same records (one per motion: update times,
familiarity at each update, the handover moment; :mod:`sandbox.eval.oodreport`
turns them into rates):

* **fitted on** ``--data`` (:func:`score_sets`): every normal trial is scored by
  a model fitted on all the *other* normal trials (leave-one-out), and its
  familiarity is ranked against the calibration of the other trials only
  (:func:`sandbox.eval.ood.rank`): a normal motion never reaches its own
  calibration, so its false alarms are those of an unseen motion. Every OOD
  trial is scored by the model of all normal trials, calibrated on all of them.
* **given** (:func:`score_with_model`, ``--model M``): every motion is streamed
  by M and ranked by M's own calibration (``fit --calibrate``); the normal set
  must then be motions M was not fitted on (e.g. another seed).

The handover moment of a trial is ``meta["handover_time"]`` when the data says
it (the synthetic OOD families: when hand and robot meet, or would have met),
else the motion's end (:meth:`~sandbox.core.IProMP.motion_end`: both partners
arrived), as in the evaluation.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from sandbox.core.familiarity import stream_record
from sandbox.eval.loocv import EvalConfig, prepare
from sandbox.eval.progress import bar
from sandbox.eval.runner import map_trials

#: Group of the normal records when OOD sets are scored (they are shared by every set).
NORMAL = "normal"

_STATE: dict = {}


def handover_time(model, stream, truth) -> float:
    """The handover moment (s from the stream's start) of one trial (module docstring)."""
    given = stream.meta.get("handover_time")
    if given is not None:
        return float(given)
    t = stream.times - stream.times[0]
    return float(t[model.motion_end(t, stream.robot, truth.human)])


def _record(model, stream, truth, dow_t: float, config: EvalConfig, labelled: bool = False,
            **about) -> dict:
    """One stream's statistics under ``model`` (:func:`~sandbox.core.familiarity.stream_record`);
    ``labelled``: also under the stream's own task (``own_stats``, what the calibration's
    cells are filed from: :mod:`sandbox.core.cells`)."""
    t = stream.times - stream.times[0]
    own = model.task_index(stream.task) if labelled else None
    times, stats, tasks, ended, *under = stream_record(
        model, t, stream.human, dow_t=dow_t, subsample=config.subsample,
        n_candidates=config.n_candidates, refine_steps=config.refine_steps, ended=True, own=own)
    return {**about, "task": stream.task, "source": stream.source,
            "end": handover_time(model, stream, truth), "times": times.tolist(),
            "stats": stats.tolist(), "ended": ended.tolist(),
            **({"own_stats": under[0].tolist()} if under else {}),
            "chosen": [model.tasks[k] for k in tasks], "tasks": list(model.tasks),
            "mean_duration": float(np.dot(model.priors,
                                          [m.mean_duration for m in model.task_models]))}


def _init(state: dict) -> None:
    _STATE.clear()
    _STATE.update(state)


def _score_job(n: int) -> dict:
    """Job ``n``: a normal trial (leave-one-out) or an OOD trial (model of all normal)."""
    s = _STATE
    kind, group, i = s["jobs"][n]
    config: EvalConfig = s["config"]
    if kind == "normal":
        fits = s["fits"][:i] + s["fits"][i + 1:]
        model = config.model().fit_demo_fits(fits, s["train"][0])
        stream, truth = s["test"][i], s["train"][i]
    else:
        if "full" not in s:
            s["full"] = config.model().fit_demo_fits(s["fits"], s["train"][0])
        model = s["full"]
        truth, stream = s["sets"][group][0][i], s["sets"][group][1][i]
    normal = kind == "normal"
    return _record(model, stream, truth, s["dow_t"], config, normal, left_out=NORMAL, trial=i,
                   held_in=normal, group=None if normal else group)


def score_sets(train, test, sets: dict, config: EvalConfig, *, dow_t: float = 0.2,
               workers: int = 1, progress: bool = False) -> list[dict]:
    """Records of every normal trial (leave-one-out) and every trial of every OOD set.

    Parameters
    ----------
    train, test : sequence of Demonstration
        The normal trials, smoothed (to fit) and causal (to stream), same order
        (:func:`sandbox.eval.datasets.load_pair`); every task needs 3 trials or more.
    sets : dict of str to (train, test)
        The OOD sets by name, each as a pair like ``train, test``.
    config : EvalConfig
        Model and stream options (``observe`` selects the modalities of every set).
    dow_t : float
        Update window (s).
    workers, progress
        Processes (fork), and progress bars on stderr.

    Returns
    -------
    list of dict
        Per trial: ``held_in`` (normal), ``group`` (the OOD set, None for normal),
        ``end`` (handover moment, s), ``times``, ``stats``, ``chosen`` and what
        :func:`sandbox.eval.ood.rank` needs.
    """
    counts = {}
    for d in train:
        counts[d.task] = counts.get(d.task, 0) + 1
    thin = sorted(k for k, n in counts.items() if n < 3)
    if thin:
        raise ValueError(f"data: expected at least 3 trials of every task (one is left out "
                         f"of each fit, two stay), got fewer of {thin}")
    train, test, fits = prepare(train, test, config)
    chosen = {g: (_select(a, config), _select(b, config)) for g, (a, b) in sets.items()}
    jobs = [("normal", None, i) for i in range(len(test))]
    jobs += [("ood", g, i) for g, (_, b) in chosen.items() for i in range(len(b))]
    state = {"train": train, "test": test, "fits": fits, "sets": chosen, "jobs": jobs,
             "config": config, "dow_t": dow_t}
    return map_trials(_score_job, len(jobs), _init, (state,), workers=workers,
                      progress=progress)


def _select(demos, config: EvalConfig) -> list:
    return list(demos) if config.observe is None else [d.select(config.observe) for d in demos]


def score_with_model(model, normal: tuple, sets: dict, config: EvalConfig, *,
                     progress: bool = False) -> list[dict]:
    """Records of ``normal`` and of every OOD set streamed by a given, calibrated ``model``.

    ``normal`` and each value of ``sets`` are ``(train, test)`` pairs as in
    :func:`score_sets`. Each record holds its ``familiarity`` under the model's
    calibration and the calibration's ``threshold`` (no ``reference``: the
    calibration motions are not at hand). The stream settings are the
    calibration's (``dow_t``, ``subsample``).
    """
    cal = getattr(model, "calibration", None)
    if cal is None:
        raise ValueError("--model: the model carries no familiarity calibration; fit it with "
                         "'python -m sandbox fit --calibrate'")
    config = replace(config, subsample=cal.subsample, observe=tuple(model.modality_names))
    groups = [(None, normal)] + list(sets.items())
    out = []
    with bar(sum(len(p[1]) for _, p in groups), "streams", progress) as shown:
        for group, (train, test) in groups:
            for i, (truth, stream) in enumerate(zip(_select(train, config),
                                                    _select(test, config), strict=True)):
                r = _record(model, stream, truth, cal.dow_t, config, left_out=NORMAL, trial=i,
                            held_in=group is None, group=group)
                index = [model.tasks.index(k) for k in r["chosen"]]
                past = np.maximum.accumulate(r["ended"]) if r["ended"] else []  # as predictors
                r["familiarity"] = [cal.familiarity(t, v, k, e) for t, v, k, e
                                    in zip(r["times"], r["stats"], index, past)]
                r["reference"], r["threshold"] = None, float(cal.threshold)
                out.append(r)
                shown.update()
    return out
