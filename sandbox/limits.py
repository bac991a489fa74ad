"""The one table of limits: every bound a user's value meets, wherever it is given.

A value reaches the project from the command line, a settings file
(``--config``), a scenario file, a sweep grid, a Gymnasium argument or a call to
the library. Each of those checks it against the entry of :data:`BOUNDS` here,
so a value refused in one place is refused in all of them with the same range
(``tests/test_limits.py`` tries every entry at and past its bounds on every
surface that takes it). The core's own constants (:mod:`sandbox.core.limits`)
are read from this table.

=====================  ==================  ======  =============================================
name                   range               unit    why
=====================  ==================  ======  =============================================
``n_basis``            2 .. 100            -       more than a few dozen over a seconds-long motion
                                                   fits noise; the fit grows as its square
``n_candidates``       3 .. 1,000          -       speed candidates per task; each costs a
                                                   likelihood factorisation per update
``refine_steps``       0 .. 100            -       golden-section steps after the grid
``subsample``          1 .. 10,000         -       keep 1 of this many observations
``regularizer``        [1e-9, 1e6]         -       relative; below 1e-9 the robot covariance is
                                                   not positive definite in floating point
``noise_scale``        (0, 1e6]            -       relative
``noise_floor``        [1e-12, 1]          m       a floor of 1 m hides the whole workspace
``signal_floor``       [1e-12, 100]        -       normalised units (training std)
``noise_floors``       [1e-12, 100]        -       per modality: m or normalised units
``jitter_floor``       (0, 1e6]            -       relative: k x the data's jitter, or null
``span_reg``           [0, 10]             -       a factor of the learned out-of-span variance,
                                                   or auto, or null (:func:`check_factor`)
``post_end``           [0, 10]             -       a factor of the learned post-end variance,
                                                   or span, or null (:func:`check_factor`)
``settle_tol``         (0, 10]             rad     or null
``arrive_tol``         (0, 10]             m       or null
``blend_rate``         [0.1, 1e6]          1/s     sigmoid rate of the blending: its span
                                                   (10 / rate + delay) fits a plan
``blend_delay``        [0, 600]            s       the longest episode (``MAX_TIME_S``)
``end_prob``           (0, 1]              -       a probability
``dow_t``              (0, 60]             s       a window; 60 s is the longest trial
``ratio``              (0, 1]              -       an observed fraction
``demos``              2 .. 10,000         -       demonstrations per task of a fit
``n_per_task``         1 .. 10,000         -       trials per task used or generated
``seed``               0 .. 2**63 - 1      -       ``numpy.random.default_rng`` seeds
``workers``            1 .. 256            -       processes
``speed``              [0.25, 4]           -       the human's speed factor in a scenario
``time_limit``         [0.1, 600]          s       an episode of ``play`` or a scenario: a
                                                   predictor's ``MAX_TIME_S``
``switch_phase``       [0.01, 1]           -       a fraction of the motion
``waypoint_t``         [0, 600]            s       a scripted waypoint's time
``position``           [-3, 3]             m       a waypoint coordinate, Baxter's base frame
``noise_m``            [0, 0.1]            m       tracker jitter; the hand moves ~0.5 m
``glitch_rate``        [0, 100]            -       tracker jumps per demonstration
``frame_hz``           (0, 1000]           Hz      the tracker's frame rate
``control_hz``         [1, 1000]           Hz      the environments' control rate
=====================  ==================  ======  =============================================

Input files (scenario, settings, grid and spec files) are bounded too, by
every reader alike: :data:`MAX_INPUT_BYTES`, :data:`MAX_INPUT_DEPTH`,
:data:`MAX_INPUT_VALUES` (counted with YAML aliases expanded, so a
"billion laughs" file is refused before anything walks it) and
:data:`MAX_GRID_POINTS` (counted before a grid is expanded).

This module imports nothing of the project and nothing outside the standard
library: the commands read it while building ``--help``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

#: Largest scenario, settings, grid or spec file read (bytes); the shipped ones are < 2 kB.
MAX_INPUT_BYTES = 2**20
#: Deepest nesting of mappings and lists in an input file (a scenario needs 5).
MAX_INPUT_DEPTH = 32
#: Most values (mappings, lists and scalars; YAML aliases expanded) in an input file.
MAX_INPUT_VALUES = 100_000
#: Most points of a sweep grid (the product of its lists, or its ``points:``).
MAX_GRID_POINTS = 1000
#: Longest dataset name or identifier (``minari:ID``), characters.
MAX_NAME_CHARS = 200


@dataclass(frozen=True)
class Bound:
    """The range of one value: ``low`` to ``high``, integers or finite numbers.

    Parameters
    ----------
    low, high : float
        The ends of the range.
    integer : bool
        Whole numbers only.
    open_low : bool
        ``low`` itself is excluded.
    unit : str
        Unit shown in messages (``"s"``, ``"m"``...).
    """

    low: float
    high: float
    integer: bool = False
    open_low: bool = False
    unit: str = ""

    def describe(self) -> str:
        """``an integer in [2, 100]`` or ``a finite number in (0, 1] s``."""
        if self.integer:
            return f"an integer in [{int(self.low)}, {int(self.high)}]"
        left = "(" if self.open_low else "["
        unit = f" {self.unit}" if self.unit else ""
        return f"a finite number in {left}{self.low:g}, {self.high:g}]{unit}"

    def contains(self, value: int | float) -> bool:
        """Whether the number ``value`` is in the range (not whether it is a number)."""
        above = value > self.low if self.open_low else value >= self.low
        return above and value <= self.high

    def check(self, value: Any, name: str, *, or_null: bool = False) -> Any:
        """``value`` as an int or float after checking it; else ``ValueError`` naming ``name``.

        Booleans, strings, None and non-finite numbers are refused; an integral
        float is accepted where an integer is expected (``5.0``). The message
        names this table; ``or_null`` adds "or null" to what it expected (the
        caller accepts None itself).
        """
        number = _as_number(value)
        if number is None or (self.integer and number != int(number)) or not self.contains(number):
            also = " or null" if or_null else ""
            raise ValueError(f"{name}: expected {self.describe()}{also}, got {_show(value)} "
                             f"(sandbox.limits)")
        return int(number) if self.integer else float(number)


def _as_number(value: Any) -> int | float | None:
    """``value`` if it is a finite int or float (numpy scalars unwrapped), else None."""
    if type(value).__module__ == "numpy" and hasattr(value, "item"):
        value = value.item()
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _show(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


#: The table (see the module docstring for the reasons).
BOUNDS: dict[str, Bound] = {
    "n_basis": Bound(2, 100, integer=True),
    "n_candidates": Bound(3, 1000, integer=True),
    "refine_steps": Bound(0, 100, integer=True),
    "subsample": Bound(1, 10_000, integer=True),
    "regularizer": Bound(1e-9, 1e6),
    "noise_scale": Bound(0, 1e6, open_low=True),
    "noise_floor": Bound(1e-12, 1.0, unit="m"),
    "signal_floor": Bound(1e-12, 100.0),
    "noise_floors": Bound(1e-12, 100.0),
    "jitter_floor": Bound(0, 1e6, open_low=True),
    "span_reg": Bound(0, 10.0),
    "post_end": Bound(0, 10.0),
    "settle_tol": Bound(0, 10.0, open_low=True, unit="rad"),
    "arrive_tol": Bound(0, 10.0, open_low=True, unit="m"),
    "blend_rate": Bound(0.1, 1e6, unit="1/s"),
    "blend_delay": Bound(0, 600.0, unit="s"),
    "end_prob": Bound(0, 1.0, open_low=True),
    "dow_t": Bound(0, 60.0, open_low=True, unit="s"),
    "ratio": Bound(0, 1.0, open_low=True),
    "demos": Bound(2, 10_000, integer=True),
    "n_per_task": Bound(1, 10_000, integer=True),
    "seed": Bound(0, 2**63 - 1, integer=True),
    "workers": Bound(1, 256, integer=True),
    "speed": Bound(0.25, 4.0),
    "time_limit": Bound(0.1, 600.0, unit="s"),
    "switch_phase": Bound(0.01, 1.0),
    "waypoint_t": Bound(0, 600.0, unit="s"),
    "position": Bound(-3.0, 3.0, unit="m"),
    "noise_m": Bound(0, 0.1, unit="m"),
    "glitch_rate": Bound(0, 100.0),
    "frame_hz": Bound(0, 1000.0, open_low=True, unit="Hz"),
    "control_hz": Bound(1.0, 1000.0, unit="Hz"),
}


def check(name: str, value: Any, label: str | None = None, *, or_null: bool = False) -> Any:
    """``value`` checked against ``BOUNDS[name]``; ``label`` (default ``name``) names it."""
    return BOUNDS[name].check(value, label or name, or_null=or_null)


def check_factor(name: str, value: Any, keyword: str, label: str | None = None) -> Any:
    """None, the word ``keyword``, or a number in ``BOUNDS[name]`` (as a float).

    For the options that take a factor of a variance learned in the fit, a word that has
    it learned otherwise, or null (``span_reg``, ``post_end``): the core, the settings
    files and the model files check them here alike. ``label`` (default ``name``) names
    the value in the ``ValueError``.
    """
    if value is None or value == keyword:
        return value
    number = _as_number(value)
    bound = BOUNDS[name]
    if number is None or not bound.contains(number):
        low, high = f"{bound.low:g}", f"{bound.high:g}"
        raise ValueError(f"{label or name}: expected a factor in [{low}, {high}], {keyword} or "
                         f"null, got {_show(value)} (sandbox.limits)")
    return float(number)
