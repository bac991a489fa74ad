"""Sweep tasks on a Dask cluster (the only module that imports ``dask.distributed``).

``scheduler="local"`` starts a ``LocalCluster`` of ``workers`` single-threaded
worker processes; any other value is the address of a running scheduler
(``tcp://host:8786``, e.g. one started by ``dask-jobqueue`` on SLURM) that the
client joins, waiting at most ``timeout`` seconds for it to answer.

The trials go to the workers as a worker plugin (:class:`_Trials`): the
scheduler hands it to every worker, including one that joins later or is
restarted after its process died, so no worker depends on another's memory.

A worker that dies marks the task it was running "suspicious"; the scheduler
gives up on a task after ``distributed.scheduler.allowed-failures`` deaths
(:class:`distributed.KilledWorker`) and :func:`~sandbox.eval.executors.run_tasks`
then retries it once. The scheduler counts a death against every task assigned
to the dead worker, running or waiting, so no more tasks are submitted than
there are worker threads (:meth:`DaskExecutor.capacity`): a task is never
charged with a death it did not cause. The local cluster sets that limit to 0,
so a task is retried once in all, as with local processes; a running scheduler
applies its own configuration first (3 by default). The local cluster's workers do not run
Dask's statistical profiler (it samples the running task every 10 ms), and
their nannies do not set ``MALLOC_TRIM_THRESHOLD_=65536`` (Dask's default,
``distributed.nanny.pre-spawn-environ``): it turns off glibc's adaptive mmap
threshold, so every array over 128 kB is mapped and unmapped afresh, and the
folds ran 1.8x slower (0.33-0.37 s per fold of the recorded set without it,
0.60-0.66 s with it). On a cluster of your own, set it to null in the workers'
Dask configuration for the same speed.
"""

from __future__ import annotations

import logging
import uuid

from sandbox.eval.tasks import Task, check_workers, install, run_task, uninstall

INSTALL_HINT = 'pip install -e ".[dask]"'
#: Configuration of the scheduler of ``scheduler="local"`` (see the module docstring).
LOCAL_CONFIG = {"distributed.scheduler.allowed-failures": 0,
                "distributed.scheduler.worker-saturation": 1.0,
                "distributed.worker.profile.enabled": False,
                "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}

try:
    import dask
    import distributed
    from distributed.diagnostics.plugin import WorkerPlugin
except ImportError as _error:  # the dask extra is not installed
    _MISSING: ImportError | None = _error
    WorkerPlugin = object
else:
    _MISSING = None


class _Trials(WorkerPlugin):
    """Installs the trials in each worker process (:func:`~sandbox.eval.tasks.install`)."""

    idempotent = True

    def __init__(self, token: str, train, test) -> None:
        self.token, self.train, self.test = token, train, test

    def setup(self, worker) -> None:
        install(self.token, self.train, self.test)

    def teardown(self, worker) -> None:
        uninstall(self.token)


class DaskExecutor:
    """Tasks on a Dask cluster (see the module docstring)."""

    def __init__(self, scheduler: str, *, workers: int = 1, timeout: float = 10.0) -> None:
        if _MISSING is not None:
            raise ValueError(f"--scheduler needs Dask: {INSTALL_HINT} (import failed: "
                             f"{_MISSING})")
        self.workers = check_workers(workers)
        self.cluster = None
        self._plugins: list[str] = []
        if scheduler == "local":
            self.client = self._local(timeout)
        else:
            self.client = self._join(scheduler, timeout)

    def _local(self, timeout: float):
        with dask.config.set(LOCAL_CONFIG):
            self.cluster = distributed.LocalCluster(
                n_workers=self.workers, threads_per_worker=1, processes=True,
                dashboard_address=None, silence_logs=logging.CRITICAL)
        return distributed.Client(self.cluster, timeout=timeout)

    @staticmethod
    def _join(address: str, timeout: float):
        try:
            return distributed.Client(address, timeout=timeout)
        except ValueError as error:
            raise ValueError(f"--scheduler: expected 'local' or the address of a running "
                             f"scheduler (e.g. tcp://host:8786), got {address!r} ({error})"
                             ) from None
        except (OSError, TimeoutError) as error:
            raise ValueError(
                f"--scheduler: no Dask scheduler answered at {address!r} within {timeout:g} s; "
                f"expected the address of a running scheduler (e.g. tcp://host:8786) or "
                f"'local' ({type(error).__name__}: {error})") from None

    def __enter__(self) -> DaskExecutor:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def load(self, token: str, train, test) -> None:
        """Install these trials too in every worker, present and future."""
        name = f"sandbox-trials-{token[:16]}"
        if name not in self._plugins:
            self.client.register_plugin(_Trials(token, list(train), list(test)), name=name)
            self._plugins.append(name)

    def slots(self) -> int:
        """Worker threads of the cluster now (at least 1, so tasks queue while it grows)."""
        return max(1, sum(self.client.nthreads().values()))

    def capacity(self) -> int:
        """Tasks kept submitted: one per worker thread. A task waiting behind another on a
        worker would count that worker's death as its own (the scheduler marks every
        task assigned to a dead worker, running or not) and could fail without having
        run; the scheduler sends a new task to an idle worker."""
        return self.slots()

    def submit(self, task: Task):
        """Start ``task`` on the cluster (a fresh key per attempt); returns its future."""
        key = f"sandbox-sweep-{task.key[:12]}-{task.folds[0]}-{uuid.uuid4().hex[:8]}"
        return self.client.submit(run_task, task, key=key, pure=False)

    def wait(self, futures: list) -> set:
        """Block until one of ``futures`` is done; returns those that are."""
        return set(distributed.wait(futures, return_when="FIRST_COMPLETED").done)

    def result(self, future):
        """The task's ``(trials, seconds)``, or its error (``KilledWorker`` if workers died)."""
        try:
            return future.result()
        finally:
            future.release()

    def _unload(self) -> None:
        for name in self._plugins:
            try:
                self.client.unregister_worker_plugin(name)
            except Exception:  # a worker gone or the scheduler closing: nothing to undo
                pass
        self._plugins = []

    def close(self) -> None:
        """Remove the trials from the workers, disconnect, stop a local cluster."""
        self._unload()
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()
