"""Argparse ``type=`` functions of the commands' options: numbers in a range, output paths.

Every numeric option is parsed by one of these, so a bad value (NaN, inf, out of
range, not a number) is refused by argparse before any work starts, with a
message naming the option (``argument --workers: expected an integer in [1, 256],
got '0'``) and exit status 2. The ranges of the shared options:

Every range is the entry of the one table of limits, :data:`sandbox.limits.BOUNDS`
(``--workers``: ``workers``; ``--seed``: ``seed``; ``--n-per-task``: ``n_per_task``;
``--demos``: ``demos``; ``--n-basis``: ``n_basis``; ``--regularizer``: ``regularizer``;
``--windows``, ``--window`` and ``--dow``: ``dow_t``; ``--ratios`` and ``--ratio``:
``ratio``; ``--time-limit``: ``time_limit``; ``--switch``: ``switch_phase``), so an
option accepts what a settings, scenario or grid file accepts for the same value.

Output paths are checked at parse time too: a file may not be an existing
folder; a file's or a folder's missing folders are made when it is written
(every command alike: ``output_file`` is ``output_file_in_new_folder``), but no
path may lie under an existing file, and the nearest existing folder must be
writable.
"""

from __future__ import annotations

import argparse
import math
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from sandbox.limits import BOUNDS

#: Longest window or observation time of an option (s): ``dow_t`` of the table.
MAX_WINDOW_S = BOUNDS["dow_t"].high
#: Longest episode of ``play`` (s): ``time_limit`` of the table.
MAX_EPISODE_S = BOUNDS["time_limit"].high
#: Most worker processes of ``evaluate``, ``tune`` and ``results``.
MAX_WORKERS = int(BOUNDS["workers"].high)
#: Largest seed (numpy accepts any non-negative integer; 64 bits is plenty).
MAX_SEED = int(BOUNDS["seed"].high)
#: Most demonstrations per task (``--n-per-task``, ``--demos``).
MAX_PER_TASK = int(BOUNDS["n_per_task"].high)
#: Basis functions per dim accepted by ``fit --n-basis``.
MAX_N_BASIS = int(BOUNDS["n_basis"].high)


def _fail(text: str, what: str) -> argparse.ArgumentTypeError:
    return argparse.ArgumentTypeError(f"expected {what}, got {text!r}")


def integer(low: int, high: int) -> Callable[[str], int]:
    """A type accepting a decimal integer in ``[low, high]``."""
    what = (f"a positive integer <= {high}" if low == 1 else
            f"a non-negative integer <= {high}" if low == 0 else
            f"an integer in [{low}, {high}]")

    def parse(text: str) -> int:
        try:
            value = int(text.strip())
        except ValueError:
            raise _fail(text, what) from None
        if not low <= value <= high:
            raise _fail(text, what)
        return value

    parse.__name__ = "integer"
    return parse


def number(low: float, high: float, *, open_low: bool = True, open_high: bool = False,
           meaning: str = "") -> Callable[[str], float]:
    """A type accepting a finite number in the interval from ``low`` to ``high``.

    ``open_low``/``open_high`` exclude the bound; ``high = math.inf`` is open.
    ``meaning`` is added to the message (e.g. the setting the option fills in).
    """
    left, right = "(" if open_low else "[", ")" if open_high or math.isinf(high) else "]"
    what = f"a finite number in {left}{low:g}, {high:g}{right}" + (f" ({meaning})" if meaning
                                                                   else "")

    def parse(text: str) -> float:
        value = _float(text, what)
        if not _inside(value, low, high, open_low, open_high):
            raise _fail(text, what)
        return value

    parse.__name__ = "number"
    return parse


def numbers(low: float, high: float, *, open_low: bool = True,
            open_high: bool = False) -> Callable[[str], tuple[float, ...]]:
    """A type accepting comma-separated finite numbers, each from ``low`` to ``high``."""
    left, right = "(" if open_low else "[", ")" if open_high else "]"
    what = f"comma-separated finite numbers in {left}{low:g}, {high:g}{right}"

    def parse(text: str) -> tuple[float, ...]:
        values = tuple(_float(x, what) for x in text.split(",") if x.strip())
        if not values or not all(_inside(v, low, high, open_low, open_high) for v in values):
            raise _fail(text, what)
        return values

    parse.__name__ = "numbers"
    return parse


def _float(text: str, what: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise _fail(text, what) from None
    if not math.isfinite(value):
        raise _fail(text, what)
    return value


def _inside(value: float, low: float, high: float, open_low: bool, open_high: bool) -> bool:
    above = value > low if open_low else value >= low
    below = value < high if open_high else value <= high
    return above and below


def output_file(text: str) -> str:
    """A type for a file to write: not an existing folder, under no file; its missing
    folders are made when it is written (one rule for every command, issue 29)."""
    return output_file_in_new_folder(text)


def output_file_in_new_folder(text: str) -> str:
    """A type for a file to write whose missing folders are made: not a folder, under no file."""
    if not text.strip() or Path(text).is_dir():
        raise _fail(text, "a file to write, not a folder")
    return _under_folders(text, Path(text).parent)


def output_folder(text: str) -> str:
    """A type for a folder to write into: not an existing file; made if missing."""
    if not text.strip():
        raise _fail(text, "a folder name")
    return _under_folders(text, Path(text))


def _under_folders(text: str, path: Path) -> str:
    """``text`` if the nearest existing one of ``path`` and its parents is a folder."""
    for part in (path, *path.parents):
        if part.exists():
            if not part.is_dir():
                raise _fail(text, f"a path under folders ({str(part)!r} is a file)")
            return _writable(text, part)
    return text


def _writable(text: str, folder: Path) -> str:
    if not os.access(folder, os.W_OK | os.X_OK):
        raise _fail(text, f"a path in a folder this user can write to ({str(folder)!r} is not)")
    return text


def bounded(name: str) -> Callable[[str], Any]:
    """The type of an option whose range is ``BOUNDS[name]`` (:mod:`sandbox.limits`)."""
    bound = BOUNDS[name]
    if bound.integer:
        return integer(int(bound.low), int(bound.high))
    return number(bound.low, bound.high, open_low=bound.open_low)


def bounded_list(name: str) -> Callable[[str], tuple[float, ...]]:
    """Comma-separated numbers, each in the range ``BOUNDS[name]``."""
    bound = BOUNDS[name]
    return numbers(bound.low, bound.high, open_low=bound.open_low)


WORKERS = bounded("workers")
SEED = bounded("seed")
PER_TASK = bounded("n_per_task")
DEMOS = bounded("demos")
N_BASIS = bounded("n_basis")
REGULARIZER = bounded("regularizer")
SECONDS = bounded("dow_t")
FRACTION = bounded("ratio")
SWITCH = bounded("switch_phase")
WINDOWS = bounded_list("dow_t")
RATIOS = bounded_list("ratio")
POSITIVE = number(0.0, math.inf)
EPISODE = bounded("time_limit")
