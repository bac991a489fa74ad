"""Command-line interface: ``python -m sandbox <command> [options]``.

Every module in :mod:`sandbox.commands` that defines ``NAME``, ``HELP``,
``add_arguments(parser)`` and ``run(args) -> int`` becomes a subcommand, so a
new command is one new file. Command modules import their heavy dependencies
inside ``run`` so that ``--help`` stays fast.
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
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module in _command_modules():
        child = sub.add_parser(module.NAME, help=module.HELP, description=module.HELP)
        module.add_arguments(child)
        child.set_defaults(_run=module.run)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Parse ``argv`` and run the chosen command; return the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not hasattr(args, "_run"):
        parser.print_help()
        return 2
    try:
        return int(args._run(args) or 0)
    except ValueError as error:  # bad input: a clear message, no traceback
        print(f"error: {error}", file=sys.stderr)
        return 2
