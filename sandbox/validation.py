"""Validators for the public boundary of every part of the project.

A neutral module (it imports only numpy, PyYAML and the standard library):
the core, the robot, the data, the viewer, the environments and the
commands all check their inputs with it, so importing it ties no part to
another (``tests/test_layering.py``).

Each ``check_*`` converts its input (arrays to a fresh float64 array: the
caller's array is never modified or aliased; scalars to a Python float, int or
bool), checks it, and raises ``ValueError`` saying what was expected and what
came: never ``TypeError`` or ``OverflowError``, whatever the input.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


#: Array kinds accepted as numbers: booleans (0/1), signed and unsigned
#: integers, floats, and object arrays that convert (e.g. lists mixing ints and
#: floats). Strings, bytes, complex numbers and dates are refused.
_NUMERIC_KINDS = "biufO"


def _describe(x: np.ndarray) -> str:
    return f"shape {x.shape}"


def short_text(text: str, limit: int = 400) -> str:
    """``text`` quoted for a one-line error message; cut to 200 characters (with its
    length) only past ``limit``, so that any real path is shown whole and a megabyte of
    garbage is not."""
    return repr(text) if len(text) <= limit else f"{text[:200]!r}... ({len(text)} characters)"


def _show(value) -> str:
    """A short repr of ``value`` for error messages."""
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def check_array(
    x: ArrayLike,
    name: str,
    ndim: int,
    *,
    shape: Sequence[int | None] | None = None,
    allow_nan: bool = False,
    min_len: int = 0,
) -> FloatArray:
    """Return ``x`` as a new float64 array after checking it.

    Parameters
    ----------
    x : array_like
        The input.
    name : str
        Name used in error messages.
    ndim : int
        Required number of dimensions.
    shape : sequence of int or None, optional
        Required size of each axis; ``None`` accepts any size.
    allow_nan : bool
        Accept NaN entries (missing values); infinities are always refused.
    min_len : int
        Minimum size of the first axis.
    """
    try:
        raw = np.asarray(x)
        if raw.dtype.kind not in _NUMERIC_KINDS:
            raise TypeError(f"dtype {raw.dtype}")
        arr = np.array(raw, dtype=np.float64, copy=True)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name}: expected an array of numbers, got {type(x).__name__}"
                         f"{'' if not hasattr(x, 'dtype') else f' of {x.dtype}'}") from None
    if arr.ndim != ndim:
        want = "x".join("n" if s is None else str(s) for s in shape) if shape else f"{ndim}-D"
        raise ValueError(f"{name}: expected a {ndim}-D array ({want}), got {_describe(arr)}")
    if shape is not None:
        for axis, size in enumerate(shape):
            if size is not None and arr.shape[axis] != size:
                wanted = tuple("n" if s is None else s for s in shape)
                raise ValueError(f"{name}: expected shape {wanted}, got {_describe(arr)}")
    if arr.ndim and arr.shape[0] < min_len:
        raise ValueError(f"{name}: expected at least {min_len} rows, got {arr.shape[0]}")
    if np.isinf(arr).any():
        raise ValueError(f"{name}: expected finite values, got infinity")
    if not allow_nan and np.isnan(arr).any():
        raise ValueError(f"{name}: expected finite values, got NaN")
    return arr


def check_times(times: ArrayLike, name: str = "times", min_len: int = 2) -> FloatArray:
    """Return a strictly increasing, finite 1-D time array (s)."""
    t = check_array(times, name, 1, min_len=min_len)
    if t.size > 1 and np.any(np.diff(t) <= 0):
        bad = int(np.argmax(np.diff(t) <= 0))
        raise ValueError(
            f"{name}: expected strictly increasing times, got t[{bad}]={t[bad]:g} "
            f"followed by t[{bad + 1}]={t[bad + 1]:g}"
        )
    return t


def check_number(value, name: str, *, low: float | None = None,
                 high: float | None = None) -> float:
    """Return ``value`` as a float after checking it is a finite real number in [low, high].

    Refuses what is not a real number even when ``float()`` would take it:
    ``None``, strings, booleans, arrays, complex numbers; ints too large for a
    float are refused too (``ValueError``, never ``TypeError``/``OverflowError``).
    """
    if isinstance(value, (bool, np.bool_, str, bytes, np.ndarray)) or value is None:
        raise ValueError(f"{name}: expected a number, got {_show(value)}")
    try:
        v = float(value)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name}: expected a number, got {_show(value)}") from None
    if not np.isfinite(v):
        raise ValueError(f"{name}: expected a finite number, got {_show(value)}")
    if (low is not None and v < low) or (high is not None and v > high):
        lo = "-inf" if low is None else f"{low:g}"
        hi = "inf" if high is None else f"{high:g}"
        raise ValueError(f"{name}: expected a number in [{lo}, {hi}], got {_show(value)}")
    return v


def check_positive(value: float, name: str, *, allow_zero: bool = False,
                   high: float | None = None) -> float:
    """Return ``value`` as a float after checking it is finite, > 0 (or >= 0) and <= ``high``."""
    bound = (">= 0" if allow_zero else "> 0") + ("" if high is None else f" and <= {high:g}")
    try:
        v = check_number(value, name)
    except ValueError:
        raise ValueError(f"{name}: expected a finite number {bound}, got {_show(value)}") from None
    if v < 0 or (v == 0 and not allow_zero) or (high is not None and v > high):
        raise ValueError(f"{name}: expected a finite number {bound}, got {_show(value)}")
    return v


def check_integer(value, name: str, low: int, high: int | None = None) -> int:
    """Return ``value`` as an int after checking it is an integer in [low, high].

    Integral floats (``5.0``) are accepted; booleans, strings, ``None``,
    non-integral or non-finite numbers are a ``ValueError``.
    """
    want = f"an integer >= {low}" if high is None else f"an integer in [{low}, {high}]"
    if isinstance(value, (bool, np.bool_, str, bytes, np.ndarray)) or value is None:
        raise ValueError(f"{name}: expected {want}, got {_show(value)}")
    if isinstance(value, (int, np.integer)):
        v = int(value)
    else:
        try:
            f = float(value)
        except (TypeError, ValueError, OverflowError):
            raise ValueError(f"{name}: expected {want}, got {_show(value)}") from None
        if not np.isfinite(f) or f != int(f):
            raise ValueError(f"{name}: expected {want}, got {_show(value)}")
        v = int(f)
    if v < low or (high is not None and v > high):
        raise ValueError(f"{name}: expected {want}, got {_show(value)}")
    return v


def check_bool(value, name: str) -> bool:
    """Return ``value`` after checking it is a boolean (``True``/``False``, numpy's too)."""
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name}: expected True or False, got {_show(value)}")
    return bool(value)


def check_fraction(value: float, name: str) -> float:
    """Return ``value`` after checking 0 < value <= 1."""
    v = check_positive(value, name)
    if v > 1:
        raise ValueError(f"{name}: expected a number in (0, 1], got {_show(value)}")
    return v


def check_mapping(value, name: str) -> dict:
    """A mapping with string keys (or None: empty) as a new dict; values are not checked."""
    if value is None:
        return {}
    if not isinstance(value, Mapping) or not all(isinstance(k, str) for k in value):
        raise ValueError(f"{name}: expected a mapping of names to numbers, got "
                         f"{type(value).__name__}")
    return dict(value)


def check_choice(value: str, name: str, choices: Sequence[str]) -> str:
    """Return ``value`` after checking it is one of ``choices`` (strings)."""
    if not isinstance(value, str) or value not in choices:
        raise ValueError(f"{name}: expected one of {list(choices)}, got {_show(value)}")
    return value


def check_rng(rng: object) -> np.random.Generator:
    """Return ``rng`` after checking it is a ``numpy.random.Generator``."""
    if not isinstance(rng, np.random.Generator):
        raise ValueError(f"rng: expected a numpy.random.Generator, got {type(rng).__name__}")
    return rng


#: Suffixes :func:`read_mapping` reads.
MAPPING_SUFFIXES = (".json", ".yaml", ".yml")


def read_mapping(path: Path, what: str = "scenario") -> Any:
    """Parse a JSON or YAML file (by suffix) within the input limits; a problem is a ValueError.

    ``what`` names the file in messages (``"scenario"``, ``"grid"``,
    ``"settings"``). The file is read by :func:`read_input_text` and parsed by
    :func:`parse_input` (size, encoding, nesting and number of values bounded
    by :mod:`sandbox.limits`). The content is returned as parsed: the caller
    checks its keys and values.
    """
    path = Path(path)
    if path.suffix.lower() not in MAPPING_SUFFIXES:
        raise ValueError(f"{what} {path}: expected a .json, .yaml or .yml file, "
                         f"got suffix {path.suffix!r}")
    return parse_input(read_input_text(path, what), path, what,
                       as_json=path.suffix.lower() == ".json")


def is_file(path: Path) -> bool:
    """``path.is_file()``, False for a name the system refuses (too long, a NUL byte)."""
    try:
        return Path(path).is_file()
    except (OSError, ValueError):
        return False


def read_input_text(path: Path, what: str) -> str:
    """The UTF-8 text of a user's input file: a regular file of at most ``MAX_INPUT_BYTES``.

    The file's type is checked before it is opened (a FIFO would block) and
    its size on the open file; no more than the limit plus one byte is read.

    Raises
    ------
    ValueError
        Not a regular file, too large, unreadable, or not UTF-8; the message
        names the file (``"<what> <path>: ..."``).
    """
    import os
    import stat

    from sandbox.limits import MAX_INPUT_BYTES

    path = Path(path)
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0)
    try:
        if not stat.S_ISREG(os.stat(path).st_mode):
            raise ValueError(f"{what} {path}: expected a regular file, got a folder, FIFO or "
                             f"device")
        with os.fdopen(os.open(path, flags), "rb") as fh:
            size = os.fstat(fh.fileno()).st_size
            data = fh.read(MAX_INPUT_BYTES + 1) if size <= MAX_INPUT_BYTES else b""
    except OSError as error:
        raise ValueError(f"{what} {path}: cannot be read ({type(error).__name__}: "
                         f"{error.strerror or error})") from None
    if size > MAX_INPUT_BYTES or len(data) > MAX_INPUT_BYTES:
        raise ValueError(f"{what} {path}: expected a file of at most {MAX_INPUT_BYTES} bytes "
                         f"(sandbox.limits.MAX_INPUT_BYTES), got {max(size, len(data))}")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as error:
        raise ValueError(f"{what} {path}: expected UTF-8 text, got byte "
                         f"0x{data[error.start]:02x} at offset {error.start}") from None


def parse_input(text: str, path: Path, what: str, *, as_json: bool) -> Any:
    """Parse the text of an input file as JSON or YAML (PyYAML's safe loader), bounded.

    Nesting deeper than ``MAX_INPUT_DEPTH`` or more than ``MAX_INPUT_VALUES``
    values (YAML aliases counted each time they are used) are refused, as is
    every syntax error; the message names the file and, for syntax, the line.
    """
    kind = "JSON" if as_json else "YAML"
    try:
        data = json.loads(text) if as_json else _yaml(text, path, what)
    except RecursionError:
        data = _TOO_DEEP
    except json.JSONDecodeError as error:
        raise ValueError(f"{what} {path}: invalid JSON at line {error.lineno}, column "
                         f"{error.colno}: {error.msg}") from None
    except ValueError as error:
        if str(error).startswith(f"{what} {path}:"):
            raise
        raise ValueError(f"{what} {path}: invalid {kind}: {_first_line(error)}") from None
    except Exception as error:  # noqa: BLE001 - the parsers raise many types on bad input
        raise ValueError(f"{what} {path}: invalid {kind} ({type(error).__name__}: "
                         f"{_first_line(error)})") from None
    try:
        check_input_size(data)
    except ValueError as error:
        raise ValueError(f"{what} {path}: {error}") from None
    return data


#: What :func:`parse_input` holds when the parser itself ran out of stack.
_TOO_DEEP = object()


def _yaml(text: str, path: Path, what: str) -> Any:
    try:
        import yaml
    except ImportError as error:  # pragma: no cover - pyyaml is a dependency
        raise ValueError(f"{what} {path}: YAML files need PyYAML (pip install pyyaml); "
                         f"or write the {what} as JSON") from error
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(error, "problem", None) or _first_line(error)
        raise ValueError(f"{what} {path}: invalid YAML{where}: {problem}") from None


def _first_line(error: BaseException) -> str:
    text = (str(error).splitlines() or [""])[0]
    return _show(text)[1:-1] if len(text) > 60 else text


def check_input_size(data: Any) -> None:
    """Refuse parsed input nested deeper than ``MAX_INPUT_DEPTH`` or with more than
    ``MAX_INPUT_VALUES`` values (aliases counted at each use); iterative, so it cannot recurse
    and stops as soon as a limit is passed."""
    from sandbox.limits import MAX_INPUT_DEPTH, MAX_INPUT_VALUES

    if data is _TOO_DEEP:
        raise ValueError(f"expected nesting at most {MAX_INPUT_DEPTH} levels deep "
                         f"(sandbox.limits.MAX_INPUT_DEPTH), got deeper than the parser goes")
    stack, count = [(data, 1)], 1
    while stack:
        value, depth = stack.pop()
        if not isinstance(value, (Mapping, list, tuple, set)):
            continue
        if depth > MAX_INPUT_DEPTH:
            raise ValueError(f"expected nesting at most {MAX_INPUT_DEPTH} levels deep "
                             f"(sandbox.limits.MAX_INPUT_DEPTH), got more")
        count += 2 * len(value) if isinstance(value, Mapping) else len(value)
        if count > MAX_INPUT_VALUES:          # counted before anything is pushed
            raise ValueError(f"expected at most {MAX_INPUT_VALUES} values "
                             f"(sandbox.limits.MAX_INPUT_VALUES; YAML aliases count at each "
                             f"use), got more")
        items = [*value.keys(), *value.values()] if isinstance(value, Mapping) else value
        stack.extend((item, depth + 1) for item in items)
