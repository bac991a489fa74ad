"""Argparse ``type=`` functions of the commands' options: numbers in a range, output paths.

Every numeric option is parsed by one of these, so a bad value (NaN, inf, out of
range, not a number) is refused by argparse before any work starts, with a
message naming the option (``argument --workers: expected an integer in [1, 256],
got '0'``) and exit status 2. The ranges of the shared options:

==================  ====================  ==========================================
option              range                 why
==================  ====================  ==========================================
``--workers``       1 .. :data:`MAX_WORKERS`   processes
``--seed``          0 .. 2**63 - 1        ``numpy.random.default_rng`` seeds
``--n-per-task``    1 .. :data:`MAX_PER_TASK`  demos per task (synthetic: generated)
``--n-basis``       2 .. :data:`MAX_N_BASIS`   basis functions per dim
``--windows`` (s)   (0, :data:`MAX_WINDOW_S`]  a window longer than a trial is no window
``--ratios``        (0, 1]                observed fractions
==================  ====================  ==========================================

Output paths are checked at parse time too: a file may not be an existing
folder and its folder must exist (``output_file``; ``output_file_in_new_folder``
makes missing folders, like ``output_folder``); a folder, or a folder to be
made, may not be or lie under an existing file.
"""

from __future__ import annotations

import argparse
import math
import os
from collections.abc import Callable
from pathlib import Path

#: Longest window or observation time of an option (s): the core's
#: ``sandbox.core.limits.MAX_DURATION_S`` (not imported: ``--help`` stays light).
MAX_WINDOW_S = 60.0
#: Longest episode of ``play`` (s).
MAX_EPISODE_S = 3600.0
#: Most worker processes of ``evaluate``, ``tune`` and ``results``.
MAX_WORKERS = 256
#: Largest seed (numpy accepts any non-negative integer; 64 bits is plenty).
MAX_SEED = 2**63 - 1
#: Most demonstrations per task (``--n-per-task``, ``--demos``).
MAX_PER_TASK = 10_000
#: Basis functions per dim accepted by ``fit --n-basis``: the core's
#: ``sandbox.core.limits.MAX_N_BASIS`` (the paper uses 21; more than a few dozen over a
#: seconds-long motion fits noise, and the fit grows as its square).
MAX_N_BASIS = 100


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
    """A type for a file to write: not an existing folder, in an existing folder."""
    path = Path(text)
    if not text.strip():
        raise _fail(text, "a file name")
    if path.is_dir():
        raise _fail(text, "a file to write, not a folder")
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise _fail(text, f"a file in an existing folder ({str(parent)!r} is not one)")
    return _writable(text, parent)


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


WORKERS = integer(1, MAX_WORKERS)
SEED = integer(0, MAX_SEED)
PER_TASK = integer(1, MAX_PER_TASK)
DEMOS = integer(2, MAX_PER_TASK)
N_BASIS = integer(2, MAX_N_BASIS)
SECONDS = number(0.0, MAX_WINDOW_S)
FRACTION = number(0.0, 1.0)
WINDOWS = numbers(0.0, MAX_WINDOW_S)
RATIOS = numbers(0.0, 1.0)
POSITIVE = number(0.0, math.inf)
EPISODE = number(0.0, MAX_EPISODE_S)
