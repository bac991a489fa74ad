"""Why trials were skipped, in one line: ``N skipped (reason in k files; ...)``.

The loaders report every unusable trial as ``"skipped <file>: <reason>"``
(:class:`~sandbox.data.recorded.SkippedTrialWarning`); :func:`summary` groups
them by the reason's first clause and counts them, and :func:`no_usable` is the
one-line error of anything left with no usable trial (the commands, the
recorded episodes' replays)::

    no usable trial in DIR: 90 skipped (missing column 'human_left_hand_x' in 90 files;
    see --observe/--spec)
"""

from __future__ import annotations

import re
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


def no_usable(data: str, skipped: list[str], what: str = "trial", hint: str = "") -> ValueError:
    """``no usable <what> in <data>: N skipped (reasons)`` as a ``ValueError`` (one line);
    ``skipped`` holds ``"skipped <file>: <reason>"`` messages, ``hint`` is appended."""
    return ValueError(f"no usable {what} in {data}: {summary(skipped)}{hint}")
