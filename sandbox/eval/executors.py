"""Where a sweep's tasks run: local worker processes or a Dask cluster, one retry per task.

A task is one configuration and a chunk of its leave-one-out folds
(:class:`~sandbox.eval.tasks.Task`); :func:`~sandbox.eval.tasks.run_task` computes it
in a worker from the trials installed there once (:mod:`sandbox.eval.tasks`, the
worker side both executors share). Two executors run tasks:

* :class:`ProcessExecutor` (default): ``workers`` single-process
  :class:`~concurrent.futures.ProcessPoolExecutor` lanes (``spawn`` start
  method), one task per lane at a time. A lane whose process dies is replaced,
  and the task it ran is known exactly: only that task is lost.
* :class:`~sandbox.eval.dask_executor.DaskExecutor` (``scheduler="local"`` or
  an address; needs ``pip install -e ".[dask]"``).

Both give each worker one BLAS thread (Dask's nanny does so by default; the
lanes are started with ``OMP_NUM_THREADS``, ``MKL_NUM_THREADS`` and
``OPENBLAS_NUM_THREADS`` set to 1), so every executor computes the same bits.

:func:`run_tasks` keeps at most ``executor.capacity()`` tasks submitted (one per
lane or Dask worker thread: a task queued behind another would die with it if
that worker's process died), retries a failed
task (its worker died, or it raised) once, then reports it as failed and goes
on with the others.

Test hook: :data:`~sandbox.eval.tasks.CRASH_HOOK` (see :mod:`sandbox.eval.tasks`).
"""

from __future__ import annotations

import os
from collections import deque
from collections.abc import Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager
from dataclasses import dataclass
from multiprocessing import get_context

from sandbox.eval.tasks import (
    CRASH_HOOK,
    Task,
    check_workers,
    install,
    install_all,
    run_task,
    uninstall,
)

#: Environment of the worker processes: one BLAS thread each, as Dask's nanny sets.
WORKER_ENV = {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
#: Attempts after the first one for a failed task.
RETRIES = 1
#: Default wait (s) for a Dask scheduler to answer.
TIMEOUT = 10.0
__all__ = ["CRASH_HOOK", "DROPPED", "RETRIES", "TIMEOUT", "WORKER_ENV", "Outcome",
           "ProcessExecutor", "Task", "check_workers", "describe", "install", "open_executor",
           "run_task", "run_tasks", "uninstall"]

#: The error of a task not run because its configuration had already failed.
DROPPED = "not run: another part of its configuration failed"


@dataclass(frozen=True)
class Outcome:
    """What came of a task: its per-fold results and compute time (s), or why it failed."""

    task: Task
    trials: list | None
    seconds: float = 0.0
    error: str | None = None


# ---------------------------------------------------------------- driver
def open_executor(workers: int = 1, scheduler: str | None = None, timeout: float = TIMEOUT):
    """An executor (a context manager): local processes, or Dask if ``scheduler`` is given.

    Parameters
    ----------
    workers : int
        Worker processes (local processes, or the workers of ``scheduler="local"``).
    scheduler : str, optional
        ``"local"`` (a Dask ``LocalCluster`` of ``workers`` single-threaded
        processes) or the address of a running Dask scheduler (``tcp://host:8786``).
    timeout : float
        Seconds to wait for the scheduler to answer.

    Raises
    ------
    ValueError
        ``workers`` < 1, ``timeout`` <= 0, Dask missing, or no scheduler at the address.
    """
    check_workers(workers)
    if not timeout > 0:
        raise ValueError(f"--scheduler-timeout: expected a positive number of seconds, "
                         f"got {timeout!r}")
    if scheduler is None:
        return ProcessExecutor(workers)
    from sandbox.eval.dask_executor import DaskExecutor

    return DaskExecutor(scheduler, workers=workers, timeout=timeout)


def run_tasks(executor, tasks: Iterable[Task], *, retries: int = RETRIES,
              dropped: set[str] | None = None) -> Iterator[Outcome]:
    """Run ``tasks`` on ``executor``; yield each one's :class:`Outcome` as it finishes.

    A task that fails is resubmitted ``retries`` times before its failure is
    yielded; the other tasks are not affected. A task not yet submitted whose
    key the caller has put in ``dropped`` is not run: it is yielded failed (:data:`DROPPED`).
    """
    pending, running, failures = deque(tasks), {}, {}
    dropped = set() if dropped is None else dropped
    while pending or running:
        room = executor.capacity() - len(running)
        while pending and room > 0:
            task = pending.popleft()
            if task.key in dropped:
                yield Outcome(task, None, error=DROPPED)
                continue
            running[executor.submit(task)] = task
            room -= 1
        for future in executor.wait(list(running)):
            task = running.pop(future)
            try:
                trials, seconds = executor.result(future)
            except Exception as error:  # a dead worker or the task's own exception
                failures[task] = failures.get(task, 0) + 1
                if failures[task] <= retries:
                    pending.appendleft(task)
                else:
                    yield Outcome(task, None, error=describe(error))
            else:
                yield Outcome(task, trials, seconds)


def describe(error: BaseException) -> str:
    """One line saying why a task failed."""
    name = type(error).__name__
    if isinstance(error, BrokenProcessPool) or name == "KilledWorker":
        return f"its worker process died ({name})"
    return f"{name}: {error}"


# ---------------------------------------------------------------- local processes
@contextmanager
def _environment(values: dict[str, str]):
    """Set environment variables for processes started inside the block."""
    saved = {k: os.environ.get(k) for k in values}
    os.environ.update(values)
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


class ProcessExecutor:
    """Tasks on ``workers`` local processes (see the module docstring)."""

    def __init__(self, workers: int) -> None:
        self.workers = check_workers(workers)
        self._context = get_context("spawn")
        self._data: dict[str, tuple[list, list]] = {}
        self._idle: list[ProcessPoolExecutor] = []
        self._busy: dict = {}

    def __enter__(self) -> ProcessExecutor:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def load(self, token: str, train, test) -> None:
        """Install these trials too in every worker (lanes restart with all of them)."""
        if token not in self._data:
            self.close()
            self._data[token] = (list(train), list(test))

    def slots(self) -> int:
        """How many tasks run at once."""
        return self.workers

    def capacity(self) -> int:
        """How many tasks may be submitted at once: one per lane (a task queued behind
        another in a lane would be lost with it if its process died)."""
        return self.workers

    def submit(self, task: Task):
        """Start ``task`` on an idle lane (a new one if none); returns its future."""
        if not self._data:
            raise RuntimeError("load the trials (load()) before submitting tasks")
        lane = self._idle.pop() if self._idle else ProcessPoolExecutor(
            1, mp_context=self._context, initializer=install_all, initargs=(self._data,))
        with _environment(WORKER_ENV):   # a new lane's process starts at its first submit
            future = lane.submit(run_task, task)
        self._busy[future] = lane
        return future

    def wait(self, futures: list) -> set:
        """Block until one of ``futures`` is done; returns those that are."""
        return wait(futures, return_when=FIRST_COMPLETED).done

    def result(self, future):
        """The task's ``(trials, seconds)``, or its error (a lane whose process died is dropped)."""
        lane = self._busy.pop(future)
        try:
            value = future.result()
        except BrokenProcessPool:
            lane.shutdown(wait=True, cancel_futures=True)
            raise
        except BaseException:
            self._idle.append(lane)
            raise
        self._idle.append(lane)
        return value

    def close(self) -> None:
        """Stop every lane's process."""
        for lane in self._idle:
            lane.shutdown(wait=True)
        for lane in self._busy.values():    # interrupted: do not wait for the running tasks
            lane.shutdown(wait=False, cancel_futures=True)
        self._idle, self._busy = [], {}
