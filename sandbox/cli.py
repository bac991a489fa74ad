"""Command-line interface: ``python -m sandbox <command> [options]``.

Every module in :mod:`sandbox.commands` that defines ``NAME``, ``HELP``,
``add_arguments(parser)`` and ``run(args) -> int`` becomes a subcommand, so a
new command is one new file. Command modules import their heavy dependencies
inside ``run`` so that ``--help`` stays fast.

Exit status: 0 on success; 2 for bad input (argparse's own errors, and a
``ValueError`` from a command: one line ``error: ...`` on stderr); 1 when a
file cannot be read or written (``OSError``) or something unexpected fails;
130 on Ctrl-C, with the one line ``error: interrupted``, in every command: :func:`main`
is the only handler (forked worker processes leave silently, see
:func:`_quiet_interrupts`); the program (:func:`run`) keeps that promise from its
first import to its exit. No traceback is printed unless ``--debug`` is
given (before or after the command name).

A value that starts with a minus (``--windows -1,2``) is given to its option
(``--windows=-1,2``), so argparse's range check names the option instead of
saying "expected one argument".
"""

from __future__ import annotations

import argparse
import atexit
import importlib
import os
import pkgutil
import re
import signal
import sys
import threading
from collections.abc import Sequence
from types import ModuleType
from typing import NoReturn

import sandbox
import sandbox.commands


def _command_modules() -> list[ModuleType]:
    modules = []
    for info in pkgutil.iter_modules(sandbox.commands.__path__):
        if info.name.startswith("_"):
            continue
        module = importlib.import_module(f"sandbox.commands.{info.name}")
        if all(hasattr(module, a) for a in ("NAME", "HELP", "add_arguments", "run")):
            modules.append(module)
    return sorted(modules, key=lambda m: m.NAME)


def build_parser() -> argparse.ArgumentParser:
    """Return the top-level parser with one subparser per command."""
    parser = argparse.ArgumentParser(
        prog="python -m sandbox",
        description="Anticipatory human-robot handover sandbox (Dynamic Interaction ProMPs).",
    )
    parser.add_argument("--version", action="version", version=sandbox.__version__)
    parser.add_argument("--debug", action="store_true", help="show tracebacks of errors")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module in _command_modules():
        child = sub.add_parser(module.NAME, help=module.HELP, description=module.HELP)
        child.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                           help="show tracebacks of errors")
        module.add_arguments(child)
        child.set_defaults(_run=module.run)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Parse ``argv`` and run the chosen command; return the exit status."""
    parser = build_parser()
    argv = _negative_values(sys.argv[1:] if argv is None else list(argv))
    try:
        args = parser.parse_args(argv)
    except SystemExit as stop:  # argparse printed the error (or the help, status 0)
        if stop.code in (0, None):
            raise
        return int(stop.code) if isinstance(stop.code, int) else 2
    if not hasattr(args, "_run"):
        parser.print_help()
        return 2
    previous = _quiet_interrupts()
    try:
        with _blas_threads():
            return int(args._run(args) or 0)
    except Exception as error:  # noqa: BLE001 - every failure becomes one line and a status
        if args.debug:
            raise
        status, text = _failure(error)
    except KeyboardInterrupt:
        if args.debug:
            raise
        print("error: interrupted", file=sys.stderr)
        return 130
    finally:
        if previous is not None:
            signal.signal(signal.SIGINT, previous)
    print(f"error: {text}", file=sys.stderr)
    return status


#: A token that starts like a negative number or list of numbers (``-1``, ``-.5,0.2``).
_NEGATIVE = re.compile(r"^-\.?\d")


def _negative_values(argv: list[str]) -> list[str]:
    """``["--windows", "-1,2"]`` -> ``["--windows=-1,2"]`` (no option of ours looks like -1)."""
    out: list[str] = []
    for token in argv:
        if (out and _NEGATIVE.match(token) and out[-1].startswith("--") and out[-1] != "--"
                and "=" not in out[-1]):
            out[-1] = f"{out[-1]}={token}"
        else:
            out.append(token)
    return out


def _quiet_interrupts():
    """Make Ctrl-C one ``KeyboardInterrupt`` here and a silent exit (130) in forked workers.

    Worker processes forked by a command (the leave-one-out pool) inherit this
    handler: there, SIGINT ends the process at once instead of printing a
    traceback per worker. Returns the handler to restore (None if unchanged:
    not the main thread, or SIGINT not at Python's default).
    """
    if (threading.current_thread() is not threading.main_thread()
            or signal.getsignal(signal.SIGINT) is not signal.default_int_handler):
        return None
    pid = os.getpid()

    def interrupt(signum, frame):
        if os.getpid() != pid:
            os._exit(130)
        raise KeyboardInterrupt

    return signal.signal(signal.SIGINT, interrupt)


#: Variables by which a user sets the BLAS threads themselves; then the CLI leaves them be.
THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def _blas_threads():
    """One BLAS thread for the command, unless the user set one of :data:`THREAD_VARIABLES`.

    The predictors' matrices are small (tens of rows): a multi-threaded BLAS spends
    more time waking its threads than computing, and with anything else running it
    oversubscribes the cores. Measured: ``demo`` 91 s with OpenBLAS's default threads
    against 15 s with one, at a load of 3 on 2 cores (issue 27).
    """
    import contextlib
    import os

    if any(os.environ.get(name) for name in THREAD_VARIABLES):
        return contextlib.nullcontext()
    from threadpoolctl import threadpool_limits

    return threadpool_limits(limits=1, user_api="blas")


def run(argv: Sequence[str] | None = None) -> NoReturn:
    """The program (``python -m sandbox``, ``handover-sandbox``): :func:`main`, then exit.

    Ctrl-C is status 130 without a traceback at every moment, not only while a
    command runs: before :func:`main` installed its handler (while it imports
    and parses), after it restored the previous one, and while the interpreter
    shuts down (joining worker processes), when Python would print a traceback
    and die of the signal itself (status -2 to a parent). In the last moments,
    after the exit handlers, it is ignored: the status is the command's.
    """
    atexit.register(_ignore_late_interrupts)   # the first registered runs last
    status: int | None = None
    while True:   # a Ctrl-C as the handler goes in (seen in CI) is caught here too
        try:
            if status is None:
                status = main(argv)
            _interrupts_end_the_process()
            break
        except KeyboardInterrupt:
            print("error: interrupted", file=sys.stderr)
            status = 130
    sys.exit(status)


def _ignore_late_interrupts() -> None:
    """Ignore SIGINT for the last moments of the interpreter's shutdown, after the exit
    handlers: Python puts a handled signal back to its default action there, and a
    Ctrl-C then would kill the process (status -2) after the work was done."""
    if signal.getsignal(signal.SIGINT) is not signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.SIG_IGN)


def _interrupts_end_the_process() -> None:
    """From now on Ctrl-C ends the process at once with status 130 (output flushed first);
    SIGINT left alone if it is not at Python's default (ignored, as under ``nohup``)."""
    if (threading.current_thread() is not threading.main_thread()
            or signal.getsignal(signal.SIGINT) is not signal.default_int_handler):
        return
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass

    def leave(signum, frame):
        os.write(2, b"error: interrupted\n")
        os._exit(130)

    signal.signal(signal.SIGINT, leave)


def _failure(error: Exception) -> tuple[int, str]:
    """Exit status and message of an error that ended a command."""
    if isinstance(error, ValueError):  # bad input: a clear message, no traceback
        return 2, str(error)
    first = (str(error).strip().splitlines() or [""])[0]
    if isinstance(error, OSError):  # "[Errno 13] Permission denied: 'x'"
        return 1, first
    if isinstance(error, ImportError) and "pip install" in first:  # a missing optional extra
        return 1, first
    return 1, (f"unexpected {type(error).__name__}: {first} (run with --debug for the "
               "traceback, and please report it)")
