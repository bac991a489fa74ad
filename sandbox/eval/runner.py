"""The processes a leave-one-out runs in: items mapped in this process or in forked workers,
on one BLAS thread, the costliest first (:func:`map_trials`).

The leave-one-out (:mod:`sandbox.eval.loocv`), the test-only and out-of-distribution
evaluations and the loading of a set's two versions (:mod:`sandbox.eval.datasets`) run
through it.
"""

from __future__ import annotations

import signal
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager
from multiprocessing import get_context

from sandbox.core.blendkernel import knots_kernel
from sandbox.eval.progress import bar

#: The BLAS limit the SIGINT block leaves in place (kept alive here).
_KEPT: dict = {}


def _init_worker(init, initargs: tuple) -> None:
    # Ctrl-C reaches the whole process group: only the parent handles it. It cancels the
    # trials not started and the pool ends with the running ones; a worker killed by the
    # signal would break the pool, whose thread then fails on the cancelled trials
    # (InvalidStateError, printed as a traceback by Python 3.11). The worker was forked
    # with SIGINT blocked (_sigint_blocked): one sent before this line stays pending and
    # is discarded here, instead of reaching the parent's handler copied into the worker.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    init(*initargs)


@contextmanager
def _sigint_blocked():
    """SIGINT held pending in this thread (and in processes forked in the block) until
    the block ends; then it is delivered here as usual."""
    before = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, before)
    _KEPT["blas"] = one_blas_thread()   # this process keeps one BLAS thread from here on


def one_blas_thread():
    """Limit BLAS to one thread until the returned object's ``restore_original_limits()``.

    The matrices of a fold are small (tens to a few hundred rows): on them a
    multi-threaded BLAS spends more time waking its threads than computing,
    and two worker processes with a BLAS thread per core oversubscribe the
    cores. Measured on the 174 recorded trials (6 per task, one process):
    2.6x less CPU time with one thread. Also a context manager.
    """
    from threadpoolctl import threadpool_limits

    return threadpool_limits(limits=1, user_api="blas")


def map_trials(run_one, n: int, init, initargs: tuple, *, workers: int = 1,
               progress: bool = False, cost=None, meanwhile=None) -> list:
    """``[run_one(i) for i in range(n)]`` after ``init(*initargs)``, in this process or in
    ``workers`` forked processes (each initialised once), on one BLAS thread, in order.

    ``progress`` draws a bar of the trials on stderr. ``cost`` (n,) estimates each item's
    work (e.g. :func:`trial_costs`): the workers then take the items one at a time,
    costliest first, so that none waits long for the others at the end (in chunks of
    ``n / (8 workers)`` in index order without it). The results are the same either way.
    Before forking, this process loads numba's kernel (once for all the workers); a
    ``meanwhile`` callable is called instead once the workers have started (e.g. loading
    that kernel while they load data: workers forked later inherit it).
    """
    results: list = [None] * n
    with one_blas_thread(), bar(n, "trials", progress) as shown:
        init(*initargs)
        if workers <= 1:
            for i in range(n):
                results[i] = run_one(i)
                shown.update()
            return results
        if meanwhile is None:
            knots_kernel()    # numba's kernels (the blend's too) loaded here, not per worker
        order = list(range(n)) if cost is None else sorted(range(n), key=lambda i: -cost[i])
        chunk = max(1, n // (8 * workers)) if cost is None else 1
        with ProcessPoolExecutor(workers, mp_context=get_context("fork"),
                                 initializer=_init_worker, initargs=(init, initargs)) as pool:
            with _sigint_blocked():      # the workers are forked here, by the first submit
                answers = pool.map(run_one, order, chunksize=chunk)
            if meanwhile is not None:
                meanwhile()
            for i, res in zip(order, answers):
                results[i] = res
                shown.update()
    return results
