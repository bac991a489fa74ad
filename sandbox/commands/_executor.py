"""The options of commands that run leave-one-out on an executor: ``--workers``,
``--scheduler`` and ``--scheduler-timeout`` (see :mod:`sandbox.eval.executors`)."""

from __future__ import annotations

import argparse

from sandbox.commands import _types


def add_arguments(parser: argparse.ArgumentParser, *, workers: int = 2) -> None:
    """Add ``--workers``, ``--scheduler`` and ``--scheduler-timeout``."""
    parser.add_argument("--workers", type=_types.WORKERS, default=workers,
                        help=f"worker processes, 1 to {_types.MAX_WORKERS} (default {workers}); "
                             "with --scheduler local, the workers of the local Dask cluster")
    parser.add_argument("--scheduler", default=None, metavar="ADDRESS|local",
                        help="run on Dask: 'local' starts a cluster of --workers processes, an "
                             "address (tcp://host:8786) joins a running scheduler (needs "
                             'pip install -e ".[dask]")')
    parser.add_argument("--scheduler-timeout", type=_types.POSITIVE, default=10.0, metavar="S",
                        help="seconds to wait for the scheduler to answer (default 10)")


def options(args: argparse.Namespace) -> dict:
    """The executor keywords of :func:`sandbox.eval.executors.open_executor` (and tune)."""
    return {"workers": args.workers, "scheduler": args.scheduler,
            "timeout": args.scheduler_timeout}
