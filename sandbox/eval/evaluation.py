"""Leave-one-out of configurations on an executor: tasks out, reports back.

An :class:`Evaluation` installs sets of trials in the executor's workers
(:mod:`sandbox.eval.executors`), splits each configuration's folds into tasks
(:func:`chunk_folds`), runs them and assembles each configuration's report
(:func:`~sandbox.eval.report.build_report`) as its last task ends. A result's
key (:func:`config_key`) hashes the full configuration, the trials
(:func:`data_token`) and the package version. Tuning (:mod:`sandbox.eval.tune`)
and sweeps (:mod:`sandbox.eval.sweep`) both evaluate through it;
:func:`write_atomic` is how their files are written.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import tempfile
from collections import Counter
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

import sandbox
from sandbox.eval.executors import DROPPED, Task, run_tasks
from sandbox.eval.loocv import EvalConfig
from sandbox.eval.report import build_report

#: Tasks per worker thread the folds are split into: configurations differ in cost (the
#: marginal likelihood takes about twice the joint one's time), and the last task to end
#: leaves the other workers idle, so tasks are kept small (a few seconds to tens of seconds).
TASKS_PER_SLOT = 32
#: Bootstrap resamples of the reports tuning and sweeps compute.
BOOTSTRAP = 200


def data_token(train, test) -> str:
    """A hash of the trials' contents (times, values, labels, modalities, meta)."""
    digest = hashlib.sha256()
    for demo in list(train) + list(test):
        for array in (demo.times, demo.human, demo.robot):
            digest.update(np.ascontiguousarray(array, dtype=float).tobytes())
        digest.update(repr((demo.task, demo.source, demo.human_names, demo.robot_names,
                            [(m.name, m.kind) for m in demo.modalities])).encode())
        if getattr(demo, "robot_space", "joint") != "joint":    # joint keeps its old tokens
            digest.update(f"robot_space {demo.robot_space}".encode())
        for name in sorted(demo.meta):
            value = demo.meta[name]
            digest.update(name.encode())
            digest.update(np.asarray(value).tobytes() if isinstance(value, np.ndarray)
                          else repr(value).encode())
    return digest.hexdigest()


def canonical(value: Any) -> str:
    """``value`` as JSON with sorted keys (other objects as their text): what keys hash."""
    return json.dumps(value, sort_keys=True, default=str)


def config_key(config: EvalConfig, token: str) -> str:
    """The key of a configuration's result: its full options, the trials, the version."""
    text = canonical({"config": config.to_dict(), "data": token,
                       "version": sandbox.__version__})
    return hashlib.sha256(text.encode()).hexdigest()[:32]


def chunk_folds(n_folds: int, n_configs: int, slots: int,
                chunk_size: int | None = None) -> list[tuple[int, ...]]:
    """The folds split into consecutive chunks, about :data:`TASKS_PER_SLOT` tasks per slot."""
    if chunk_size is None:
        per_config = math.ceil(TASKS_PER_SLOT * slots / max(1, n_configs))
        chunk_size = math.ceil(n_folds / max(1, min(n_folds, per_config)))
    if chunk_size < 1:
        raise ValueError(f"chunk_size: expected a positive integer, got {chunk_size!r}")
    return [tuple(range(i, min(i + chunk_size, n_folds))) for i in range(0, n_folds, chunk_size)]


class Evaluated(NamedTuple):
    """A configuration's evaluation: its key and report, or why it failed."""

    key: str
    config: EvalConfig
    report: dict | None
    error: str | None


class Evaluation:
    """Leave-one-out of configurations on sets of trials, on an executor.

    Parameters
    ----------
    executor : ProcessExecutor or DaskExecutor
        Where the tasks run (:func:`~sandbox.eval.executors.open_executor`).
    dataset : str
        The ``dataset`` label of the reports.
    chunk_size : int, optional
        Folds per task (default: see :func:`chunk_folds`).
    """

    def __init__(self, executor, *, dataset: str = "", chunk_size: int | None = None) -> None:
        self.executor, self.dataset, self.chunk_size = executor, dataset, chunk_size
        self._folds: dict[str, int] = {}

    def add(self, train, test) -> str:
        """Install a set of trials in the executor's workers; returns its token.

        ``train`` and ``test`` are the same trials preprocessed for training and as
        test streams (:func:`~sandbox.eval.datasets.load_pair`).
        """
        if len(train) != len(test) or any(a.source != b.source or a.task != b.task
                                          for a, b in zip(train, test)):
            raise ValueError("train and test: expected the same trials in the same order")
        counts = Counter(d.task for d in train)
        if not counts or min(counts.values()) < 3:
            raise ValueError(f"trials: expected at least 3 per task for leave-one-out (each fold "
                             f"fits on the 2 or more others), got {dict(counts)}")
        token = data_token(train, test)
        if token not in self._folds:
            self.executor.load(token, train, test)
            self._folds[token] = len(train)
        return token

    def run(self, jobs: Sequence[tuple[EvalConfig, str]], *,
            on_trials: Callable[[int], None] | None = None) -> Iterator[Evaluated]:
        """Evaluate each ``(config, token)``; yield each distinct one as its last task ends.

        ``on_trials(n)`` is called as each task of ``n`` trials ends (e.g. a
        progress bar's ``update``).
        """
        jobs = list({config_key(c, t): (c, t) for c, t in jobs}.items())
        tasks: list[Task] = []
        for key, (config, token) in jobs:
            n_folds = self._folds[token]
            for folds in chunk_folds(n_folds, len(jobs), self.executor.slots(), self.chunk_size):
                tasks.append(Task(key, config, folds, token))
        expected = {key: sum(t.key == key for t in tasks) for key, _ in jobs}
        configs = {key: config for key, (config, _) in jobs}
        parts: dict[str, list] = {key: [] for key, _ in jobs}
        failed: set[str] = set()     # configurations whose other tasks need not run
        for outcome in run_tasks(self.executor, tasks, dropped=failed):
            key = outcome.task.key
            parts[key].append(outcome)
            if on_trials is not None:
                on_trials(len(outcome.task.folds))
            if outcome.error is not None:
                failed.add(key)
            if len(parts[key]) == expected[key]:
                yield self._assemble(key, configs[key], parts.pop(key))

    def _assemble(self, key: str, config: EvalConfig, outcomes: list) -> Evaluated:
        errors = sorted({o.error for o in outcomes if o.error not in (None, DROPPED)})
        if errors:
            return Evaluated(key, config, None, "; ".join(errors))
        outcomes = sorted(outcomes, key=lambda o: o.task.folds[0])
        trials = [t for o in outcomes for t in o.trials]
        seconds = sum(o.seconds for o in outcomes)
        report = build_report(trials, config.to_dict(), self.dataset, seconds, n_boot=BOOTSTRAP)
        return Evaluated(key, config, report, None)


def write_atomic(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` through a temporary file in the same folder."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
