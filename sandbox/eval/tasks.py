"""The worker side of a sweep: tasks, the trials installed in a worker, running a task.

A task is one configuration and a chunk of its leave-one-out folds
(:class:`Task`); :func:`run_task` computes it in a worker from the trials
installed there once (:func:`install`). Both executors
(:mod:`sandbox.eval.executors`, :mod:`sandbox.eval.dask_executor`) run tasks
with these functions.

Test hook: a worker running a task whose configuration key starts with
``$SANDBOX_TEST_SWEEP_CRASH`` kills its own process (``os._exit``). With
``KEY@FILE`` it dies only while ``FILE`` has no line yet, with ``KEY*N@FILE``
while it has fewer than N lines, appending one line before dying (so the
file counts the deaths). Several entries are separated by commas.
"""

from __future__ import annotations

import os
import threading
import time
from dataclasses import dataclass
from pathlib import Path

from sandbox.eval.loocv import EvalConfig, fold, prepare
from sandbox.validation import check_integer

#: Environment variable of the test hook that crashes chosen sweep tasks.
CRASH_HOOK = "SANDBOX_TEST_SWEEP_CRASH"


@dataclass(frozen=True)
class Task:
    """One unit of work: folds ``folds`` of the configuration keyed ``key`` on trials ``data``."""

    key: str
    config: EvalConfig
    folds: tuple[int, ...]
    data: str



# ---------------------------------------------------------------- worker side
_DATA: dict[str, tuple[list, list]] = {}
_PREPARED: dict = {}
_KEEP = 4   # configurations whose prepared trials a worker keeps
_FK: list = []
_LOCK = threading.Lock()   # a Dask worker may run tasks on several threads


def install(token: str, train, test) -> None:
    """Keep the trials ``token`` names in this process (workers call it once)."""
    _DATA[token] = (list(train), list(test))


def install_all(data: dict[str, tuple[list, list]]) -> None:
    """:func:`install` every entry of ``data`` (token -> (train, test)); a lane's initializer."""
    for token, (train, test) in data.items():
        install(token, train, test)


def uninstall(token: str) -> None:
    """Forget the trials ``token`` names, and what was prepared from them."""
    _DATA.pop(token, None)
    for ident in [k for k in _PREPARED if k[0] == token]:
        del _PREPARED[ident]


def run_task(task: Task) -> tuple[list[dict], float]:
    """The results of the task's folds, in order, and the seconds they took (in a worker)."""
    from sandbox.robot import BaxterKinematics

    _maybe_crash(task.key)
    start = time.perf_counter()
    if task.data not in _DATA:
        raise RuntimeError(f"trials {task.data[:12]} are not installed in this worker "
                           f"(pid {os.getpid()})")
    ident = (task.data, task.config)
    with _LOCK:
        if ident not in _PREPARED:
            while len(_PREPARED) >= _KEEP:
                _PREPARED.pop(next(iter(_PREPARED)))
            _PREPARED[ident] = prepare(*_DATA[task.data], task.config)
        train, test, fits = _PREPARED[ident]
        if not _FK:
            _FK.append(BaxterKinematics().fk)
        fk = _FK[0]
    trials = [fold(train, test, fits, task.config, i, fk) for i in task.folds]
    return trials, time.perf_counter() - start


def _maybe_crash(key: str) -> None:
    """The test hook (see the module docstring)."""
    for entry in filter(None, os.environ.get(CRASH_HOOK, "").split(",")):
        head, _, marker = entry.partition("@")
        prefix, _, times = head.partition("*")
        if not key.startswith(prefix):
            continue
        if marker:
            deaths = Path(marker).read_text().count("\n") if Path(marker).exists() else 0
            if deaths >= int(times or 1):
                continue
            with open(marker, "a") as f:
                f.write(f"{os.getpid()}\n")
        os._exit(3)


def check_workers(workers) -> int:
    """``workers`` as an int after checking it is an integer >= 1."""
    return check_integer(workers, "--workers", 1)
