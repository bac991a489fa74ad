"""Command-line interface: ``python -m sandbox <command> [options]``.

Every module in :mod:`sandbox.commands` that defines ``NAME``, ``HELP``,
``add_arguments(parser)`` and ``run(args) -> int`` becomes a subcommand, so a
new command is one new file. Command modules import their heavy dependencies
inside ``run`` so that ``--help`` stays fast.

Exit status: 0 on success; 2 for bad input (argparse's own errors, and a
``ValueError`` from a command: one line ``error: ...`` on stderr); 1 when a
file cannot be read or written (``OSError``) or something unexpected fails;
130 on Ctrl-C. No traceback is printed unless ``--debug`` is given (before
or after the command name).
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import sys
from collections.abc import Sequence
from types import ModuleType

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
    try:
        args = parser.parse_args(argv)
    except SystemExit as stop:  # argparse printed the error (or the help, status 0)
        if stop.code in (0, None):
            raise
        return int(stop.code) if isinstance(stop.code, int) else 2
    if not hasattr(args, "_run"):
        parser.print_help()
        return 2
    try:
        return int(args._run(args) or 0)
    except Exception as error:  # noqa: BLE001 - every failure becomes one line and a status
        if args.debug:
            raise
        status, text = _failure(error)
    except KeyboardInterrupt:
        if args.debug:
            raise
        status, text = 130, "interrupted"
    print(f"error: {text}", file=sys.stderr)
    return status


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
