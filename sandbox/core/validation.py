"""Validators for the public boundary of the core.

Each ``check_*`` converts its input to a fresh float64 array (the caller's
array is never modified or aliased), checks it, and raises ``ValueError`` saying
what was expected and what came.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


def _describe(x: np.ndarray) -> str:
    return f"shape {x.shape}"


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
        arr = np.array(x, dtype=np.float64, copy=True)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{name}: expected an array of numbers, got {type(x).__name__}") from error
    if arr.ndim != ndim:
        want = "x".join("n" if s is None else str(s) for s in shape) if shape else f"{ndim}-D"
        raise ValueError(f"{name}: expected a {ndim}-D array ({want}), got {_describe(arr)}")
    if shape is not None:
        for axis, size in enumerate(shape):
            if size is not None and arr.shape[axis] != size:
                want = tuple("n" if s is None else s for s in shape)
                raise ValueError(f"{name}: expected shape {want}, got {_describe(arr)}")
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


def check_positive(value: float, name: str, *, allow_zero: bool = False) -> float:
    """Return ``value`` as a float after checking it is finite and > 0 (or >= 0)."""
    try:
        v = float(value)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{name}: expected a number, got {value!r}") from error
    if not np.isfinite(v) or v < 0 or (v == 0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"{name}: expected a finite number {bound}, got {value!r}")
    return v


def check_fraction(value: float, name: str) -> float:
    """Return ``value`` after checking 0 < value <= 1."""
    v = check_positive(value, name)
    if v > 1:
        raise ValueError(f"{name}: expected a number in (0, 1], got {value!r}")
    return v


def check_choice(value: str, name: str, choices: Sequence[str]) -> str:
    """Return ``value`` after checking it is one of ``choices``."""
    if value not in choices:
        raise ValueError(f"{name}: expected one of {list(choices)}, got {value!r}")
    return value
