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
import re
import sys
from collections import Counter
from collections.abc import Iterable

#: ``skipped <file>: <reason>`` (the file name ends at the first ``.csv: ``, or ``: ``).
_MESSAGE = re.compile(r"^skipped (?P<file>.+?\.csv|[^:]+): (?P<reason>.*)$", re.S)
#: Groups shown in a summary line; the others are counted as "N other reasons".
MAX_GROUPS = 3
#: Words of a reason that the observation options (--observe, --spec) can fix.
_SPEC_WORDS = ("column", "modality", "samples of")
#: The unit a time column looks like (:func:`sandbox.core.limits.check_duration`'s hint).
_UNIT = re.compile(r"looks like (milliseconds|microseconds|nanoseconds)")
#: ``--time-unit`` (and the spec's ``time_unit``) of each unit the hint names.
_UNIT_OPTION = {"milliseconds": "ms", "microseconds": "us", "nanoseconds": "ns"}


def add_argument(parser: argparse.ArgumentParser) -> None:
    """Add ``--verbose`` (list every skipped trial with its reason)."""
    parser.add_argument("--verbose", action="store_true",
                        help="list every skipped trial with its reason (default: one summary "
                             "line)")


def split(message: str) -> tuple[str, str]:
    """``"skipped f.csv: missing column 'x'; ..."`` -> ``("f.csv", "missing column 'x'; ...")``."""
    match = _MESSAGE.match(str(message))
    return (match["file"], match["reason"]) if match else ("?", str(message))


def short(reason: str) -> str:
    """The first clause of a reason (before ``;``, `` (`` or ``:``), the key it is grouped by;
    with the fix when the times look like another unit than seconds (issue 26: the hint
    was only in ``--verbose``)."""
    first = re.split(r";| \(|: ", reason, maxsplit=1)[0].strip() or reason
    unit = _UNIT.search(reason)
    if unit is None:
        return first
    return (f"{first} looks like {unit[1]} (--time-unit {_UNIT_OPTION[unit[1]]}, or "
            f"time_unit: {_UNIT_OPTION[unit[1]]} in a spec)")


def summary(skipped: Iterable[str]) -> str:
    """``"90 skipped (missing column 'x' in 90 files; see --observe/--spec)"``."""
    groups = Counter(short(split(m)[1]) for m in skipped)
    total = sum(groups.values())
    parts = [f"{reason} in {n} file{'s' if n > 1 else ''}"
             for reason, n in groups.most_common(MAX_GROUPS)]
    rest = len(groups) - MAX_GROUPS
    if rest > 0:
        parts.append(f"{rest} other reason{'s' if rest > 1 else ''}")
    if any(word in reason for reason in groups for word in _SPEC_WORDS):
        parts.append("see --observe/--spec")
    return f"{total} skipped ({'; '.join(parts)})" if total else "0 skipped"


def no_usable(data: str, skipped: list[str], what: str = "trial",
              verbose: bool = False) -> ValueError:
    """The error of a command left with no usable trial (``--verbose`` for every file)."""
    return ValueError(f"no usable {what} in {data}: {summary(skipped)}"
                      + ("; --verbose lists every file" if skipped and not verbose else ""))


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
