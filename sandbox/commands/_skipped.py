"""Trials a data-reading command could not use: one summary line, the details on ``--verbose``.

The loaders report every unusable trial as ``"skipped <file>: <reason>"``
(:class:`~sandbox.data.recorded.SkippedTrialWarning`). A command prints one
line that groups them by the reason's first clause and counts them::

    no usable trial in DIR: 90 skipped (missing column 'human_left_hand_x' in 90 files;
    see --observe/--spec)

and lists every file with its full reason only with ``--verbose``.
"""

from __future__ import annotations

import argparse
import sys


def split(message: str) -> tuple[str, str]:
    """:func:`sandbox.data.skipped.split` (imported when used: ``--help`` stays light)."""
    from sandbox.data import skipped

    return skipped.split(message)


def short(reason: str) -> str:
    """:func:`sandbox.data.skipped.short`."""
    from sandbox.data import skipped

    return skipped.short(reason)


def summary(messages) -> str:
    """:func:`sandbox.data.skipped.summary`: ``"90 skipped (missing column 'x' in 90 files;
    see --observe/--spec)"``."""
    from sandbox.data import skipped

    return skipped.summary(messages)


def add_argument(parser: argparse.ArgumentParser) -> None:
    """Add ``--verbose`` (list every skipped trial with its reason)."""
    parser.add_argument("--verbose", action="store_true",
                        help="list every skipped trial with its reason (default: one summary "
                             "line)")


def no_usable(data: str, skipped: list[str], what: str = "trial",
              verbose: bool = False) -> ValueError:
    """The error of a command left with no usable trial (``--verbose`` for every file)."""
    from sandbox.data.skipped import no_usable as error

    return error(data, skipped, what,
                 "; --verbose lists every file" if skipped and not verbose else "")


def report(skipped: list[str], verbose: bool, kept: int, stream=None) -> None:
    """Tell what was skipped: every file with ``verbose``, else one line (nothing if none were
    skipped, or none kept: the command's error then says it)."""
    stream = sys.stderr if stream is None else stream
    if verbose:
        for message in skipped:
            file, reason = split(message)
            print(f"skipped {file}: {reason}", file=stream)
    elif skipped and kept:
        print(f"note: {kept} trials used, {summary(skipped)}; --verbose lists them",
              file=stream)
