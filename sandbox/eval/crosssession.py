"""Cross-session evaluation: fit on some sessions, predict the trials of another.

Two evaluations of ``python -m sandbox evaluate`` use it:

* ``--data A --test B`` (:func:`run_cross_session`): one model of every task
  fitted on all trials of A (with the options the leave-one-out uses), every
  trial of B predicted by it. The report's ``config`` says
  ``mode: cross-session``, ``train: A``, ``test: B`` and the trials of each.
* ``--data ROOT`` with ``ROOT/<session>/<task>/<trial>.csv``
  (:func:`run_leave_one_session_out`): each session predicted by a model
  fitted on all the other sessions; ``mode: leave-one-session-out`` and
  ``sessions``. The report pools every trial, like the leave-one-out, and
  :func:`per_session` breaks the figures down by session.

Each trial is measured exactly as one fold of the leave-one-out measures it
(:func:`~sandbox.eval.loocv.evaluate_trial`, through the test-only runner
:func:`~sandbox.eval.heldout.run_heldout`): the training demos are the smoothed
versions, the streams predicted the causal ones (only samples received so far),
and the true duration is the smoothed trial's motion end. Everything the model
learns, the normaliser of signal modalities (EMG) included, comes from the
training sessions alone (:meth:`~sandbox.core.IProMP.fit_demo_fits`).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sandbox.eval import heldout
from sandbox.eval.loocv import EvalConfig, prepare
from sandbox.eval.runner import one_blas_thread

#: ``report["config"]["mode"]`` of ``--data A --test B``.
CROSS_SESSION = "cross-session"
#: ``report["config"]["mode"]`` of a folder of sessions.
LEAVE_ONE_SESSION_OUT = "leave-one-session-out"
#: Measures of :func:`per_session`, by section.
SESSION_MEASURES = {"static": ("e_p", "e_q", "e_phi", "recognition"),
                    "dynamic": ("e_p", "e_q", "e_phi", "recognition", "time_to_correct"),
                    "oracle": ("e_p", "e_q")}


@dataclass(frozen=True)
class TrialSet:
    """The trials of one set (or session) in the two versions an evaluation needs.

    Attributes
    ----------
    name : str
        What the report calls it (a folder, ``synthetic:NAME`` or a session's name).
    train : tuple of Demonstration
        Preprocessed for training (smoothed): fitted on, and the true durations.
    test : tuple of Demonstration
        The same trials in the same order as test streams (causal).
    """

    name: str
    train: tuple
    test: tuple

    def __post_init__(self) -> None:
        if len(self.train) != len(self.test) or any(
                a.source != b.source or a.task != b.task for a, b in zip(self.train, self.test)):
            raise ValueError(f"{self.name}: expected the same trials in train and test, "
                             "in the same order")

    def tasks(self) -> list[str]:
        """The tasks of its trials, in order of appearance."""
        return list(dict.fromkeys(d.task for d in self.train))


def load_sets(data: str | Path, **options) -> tuple[list[TrialSet], list[str]]:
    """The sessions of a folder of sessions, or ``data`` as one set.

    ``options`` go to :func:`~sandbox.eval.datasets.load_pair` (``seed``, ``tasks``,
    ``n_per_task``, ``spec``, ``observe``, ``cache``, ``progress``), for every
    session alike. Returns the sets (sessions sorted by name, each named by its
    folder's name) and the skipped trials of all of them.
    """
    from sandbox.data.sessions import find_sessions
    from sandbox.eval.datasets import load_pair

    folders = [] if str(data).startswith("synthetic:") else find_sessions(data)
    sets, skipped = [], []
    for name, where in ([(f.name, f) for f in folders] or [(str(data), data)]):
        try:
            train, test, dropped = load_pair(str(where), **options)
        except ValueError as error:         # e.g. --tasks: say which session lacks them
            raise ValueError(f"session {name}: {error}" if folders else str(error)) from None
        sets.append(TrialSet(name, tuple(train), tuple(test)))
        skipped += dropped
    return sets, skipped


def check_tasks(fit: Sequence[TrialSet], test: TrialSet, option: str = "--test") -> None:
    """``ValueError`` unless every task of ``test`` has trials in ``fit``."""
    known = list(dict.fromkeys(t for s in fit for t in s.tasks()))
    missing = [t for t in test.tasks() if t not in known]
    if missing:
        names = ", ".join(s.name for s in fit)
        hint = "; choose some with --tasks" if len(missing) < len(test.tasks()) else ""
        raise ValueError(f"{option}: {test.name} has tasks {missing} that {names} has no "
                         f"trials of (it has {known}){hint}")


def fit_model(fit: Sequence[TrialSet], config: EvalConfig, *, progress: bool = False):
    """One :class:`~sandbox.core.IProMP` of every task fitted on all trials of ``fit``
    (their training versions, ``config.observe`` selected), as a leave-one-out fold fits."""
    demos = [d for s in fit for d in s.train]
    if not demos:
        raise ValueError("fit: expected trials to fit on, got none")
    demos, _, fits = prepare(demos, [], config, progress=progress)
    try:
        return config.model().fit_demo_fits(fits, demos[0])
    except ValueError as error:
        raise ValueError(f"fitting on {', '.join(s.name for s in fit)}: {error}") from None


def run_cross_session(fit: Sequence[TrialSet], test: TrialSet, config: EvalConfig, *,
                      workers: int = 1, progress: bool = False) -> tuple[list[dict], float]:
    """Fit on all trials of ``fit``, predict every trial of ``test``.

    Parameters
    ----------
    fit : sequence of TrialSet
        The sets (sessions) fitted on, pooled.
    test : TrialSet
        The set predicted; its tasks must be among those of ``fit``.
    config : EvalConfig
        The model and predictor options, ratios and windows (as the leave-one-out's).
    workers : int
        Processes (fork) predicting the trials; 1 runs in this process.
    progress : bool
        Show progress bars on stderr.

    Returns
    -------
    trials : list of dict
        One :func:`~sandbox.eval.loocv.evaluate_trial` result per trial of ``test``.
    runtime : float
        Wall time (s), the fit included.
    """
    check_tasks(fit, test)
    start = time.perf_counter()
    with one_blas_thread():
        model = fit_model(fit, config, progress=progress)
    trials, _ = heldout.run_heldout(model, _select(test.train, config),
                                    _select(test.test, config), config, workers=workers,
                                    progress=progress)
    return trials, time.perf_counter() - start


def _select(demos, config: EvalConfig) -> list:
    """The demonstrations with the modalities ``config.observe`` names (all if None)."""
    return [d.select(config.observe) for d in demos] if config.observe is not None \
        else list(demos)


def run_leave_one_session_out(sessions: Sequence[TrialSet], config: EvalConfig, *,
                              workers: int = 1,
                              progress: bool = False) -> tuple[list[dict], float]:
    """Each session predicted by a model fitted on all the others (:func:`run_cross_session`).

    Returns every trial's result, session by session, each with its ``session``
    (the :attr:`TrialSet.name`), and the total wall time (s). Fewer than two
    sessions, or a session with a task the others have no trials of, is a
    ``ValueError`` before anything runs.
    """
    sessions = list(sessions)
    if len(sessions) < 2:
        raise ValueError(f"sessions: expected at least 2 to leave one out, got {len(sessions)}")
    for i, session in enumerate(sessions):
        check_tasks(sessions[:i] + sessions[i + 1:], session, "--data")
    trials, runtime = [], 0.0
    for i, session in enumerate(sessions):
        done, seconds = run_cross_session(sessions[:i] + sessions[i + 1:], session, config,
                                          workers=workers, progress=progress)
        trials += [{**r, "session": session.name} for r in done]
        runtime += seconds
    return trials, runtime


def describe_cross(config: EvalConfig, fit: Sequence[TrialSet], test: TrialSet,
                   train: str | None = None) -> dict:
    """The report's ``config`` of ``--data A --test B``: the options, ``mode``, ``train``
    (``train``, default the names of ``fit``), ``test`` and the trials of each
    (``n_train``, ``n_test``; per task in ``*_tasks``); ``train_sessions`` names the
    sessions of a ``fit`` of several."""
    demos = [d for s in fit for d in s.train]
    out = {**config.to_dict(), "mode": CROSS_SESSION,
           "train": ", ".join(s.name for s in fit) if train is None else train,
           "test": test.name, "n_train": len(demos), "n_test": len(test.train),
           "train_tasks": _counts(demos), "test_tasks": _counts(test.train)}
    if len(fit) > 1:
        out["train_sessions"] = [s.name for s in fit]
    return out


def describe_sessions(config: EvalConfig, sessions: Sequence[TrialSet]) -> dict:
    """The report's ``config`` of a leave-one-session-out: the options, ``mode``,
    ``sessions`` (names, in order) and each one's trials (``session_trials``)."""
    return {**config.to_dict(), "mode": LEAVE_ONE_SESSION_OUT,
            "sessions": [s.name for s in sessions],
            "session_trials": {s.name: len(s.train) for s in sessions}}


def _counts(demos) -> dict[str, int]:
    tasks = list(dict.fromkeys(d.task for d in demos))
    return {t: sum(d.task == t for d in demos) for t in tasks}


def per_trial(trials: list[dict]) -> list[dict]:
    """:func:`~sandbox.eval.heldout.per_trial`, each row with its ``session`` (if any)."""
    rows = heldout.per_trial(trials)
    return [{**row, "session": r["session"]} if "session" in r else row
            for row, r in zip(rows, trials)]


def per_session(trials: list[dict]) -> dict[str, dict]:
    """Each session's figures, computed as the report's ``"mean"`` entries are (the mean
    over the session's tasks of each task's mean), so they equal those of the report of
    ``--data <the others> --test <session>``.

    Returns ``{session: {"n_trials": {task: n}, "static": {ratio: {measure: value}},
    "dynamic": {window: {...}}, "oracle": {...}}}``, the measures of
    :data:`SESSION_MEASURES` (e_p in m, e_q in rad, e_phi in s, recognition a fraction).
    """
    out: dict[str, dict] = {}
    for name in dict.fromkeys(r["session"] for r in trials):
        rows = [r for r in trials if r["session"] == name]
        tasks = list(dict.fromkeys(r["task"] for r in rows))
        entry: dict = {"n_trials": {t: sum(r["task"] == t for r in rows) for t in tasks}}
        for section in ("static", "dynamic"):
            entry[section] = {key: _macro(rows, tasks, lambda r, s=section, k=key: r[s][k],
                                          SESSION_MEASURES[section])
                              for key in rows[0][section]}
        entry["oracle"] = _macro(rows, tasks, lambda r: r["oracle"], SESSION_MEASURES["oracle"])
        out[name] = entry
    return out


def _macro(rows: list[dict], tasks: list[str], get, keys) -> dict[str, float | None]:
    """The mean over tasks of each task's mean (as :func:`~sandbox.eval.report.build_report`)."""
    groups = np.array([r["task"] for r in rows])
    out = {}
    for key in keys:
        raw = [get(r)[key] for r in rows]
        if all(v is None for v in raw):       # not applicable (e_q in task space)
            out[key] = None
            continue
        values = np.array(raw, dtype=float)
        out[key] = float(np.mean([values[groups == g].mean() for g in tasks]))
    return out
