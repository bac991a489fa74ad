"""Grids of evaluation options for :mod:`sandbox.eval.sweep`: the YAML (or JSON) file.

A grid file is either lists of values, whose Cartesian product is swept::

    n_basis: [15, 21]
    noise_floor: [0.01, 0.02]
    likelihood: [joint, marginal]
    observe: [hand, "hand,arm"]

or an explicit list of points (each a mapping of option to one value)::

    points:
      - {n_basis: 15, likelihood: joint}
      - {n_basis: 21, likelihood: marginal, observe: [hand, arm]}

Options (unnamed ones keep the base configuration's value, by default
:class:`~sandbox.eval.loocv.EvalConfig`'s):

* model (:class:`~sandbox.core.IProMP`): ``n_basis``, ``regularizer``,
  ``noise_scale``, ``noise_floor``, ``signal_floor``, ``noise_floors`` (a
  mapping modality -> floor, e.g. ``{arm: 0.02}``), ``settle_tol``,
  ``arrive_tol`` (``null`` for none);
* predictor (:class:`~sandbox.core.DynamicPredictor`): ``likelihood``
  (joint | marginal), ``window`` (all | latest; ``window_mode`` is the same),
  ``n_candidates``, ``refine_steps``, ``blend_rate``, ``blend_delay``,
  ``until_end``, ``end_prob``, ``subsample``;
* ``observe``: the modalities observed (a list or ``"hand,arm"``);
* scoring: ``dow_t`` (s), the dynamic window evaluated and scored, and
  ``ratio``, the static formulation's observed fraction (defaults those of
  :func:`~sandbox.eval.tune.tune`, 0.2 s and 0.3).

YAML 1.1 reads ``1e-3`` as a string: numbers are converted and checked here, so
``1e-3`` and ``0.001`` are the same value.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Mapping
from dataclasses import replace
from math import prod
from pathlib import Path
from typing import Any

from sandbox.core.predictor import LIKELIHOODS, WINDOW_MODES
from sandbox.core.shrinkage import SHRINKAGE
from sandbox.eval.loocv import EvalConfig
from sandbox.eval.tune import RATIO, WINDOW
from sandbox.limits import BOUNDS, MAX_GRID_POINTS
from sandbox.validation import check_choice

#: Grid names that are another name of an :class:`EvalConfig` field.
ALIASES = {"window": "window_mode"}


def _from_yaml(value: Any) -> Any:
    """A number YAML 1.1 left as a string (``1e-3``, ``1e2``) as a float; anything else as is."""
    if isinstance(value, str):
        try:
            return float(value)
        except ValueError:
            return value
    return value


def _bounded(key: str) -> Callable[[str, Any], Any]:
    """The check of option ``key``: its entry of :data:`sandbox.limits.BOUNDS`."""
    return lambda name, value: BOUNDS[key].check(_from_yaml(value), name)


def _optional(key: str) -> Callable[[str, Any], Any]:
    return lambda name, value: (None if value is None else
                                BOUNDS[key].check(_from_yaml(value), name, or_null=True))


def _flag(name: str, value: Any) -> bool:
    if not isinstance(value, bool):
        raise ValueError(f"{name}: expected true or false, got {value!r}")
    return value


def _choice(choices) -> Callable[[str, Any], str]:
    return lambda name, value: check_choice(value, name, choices)


def _modalities(name: str, value: Any) -> tuple[str, ...]:
    names = value.split(",") if isinstance(value, str) else value
    if not isinstance(names, list | tuple) or not all(isinstance(n, str) for n in names):
        raise ValueError(f"{name}: expected modality names (a list or \"hand,arm\"), "
                         f"got {value!r}")
    names = tuple(n.strip() for n in names if n.strip())
    if not names:
        raise ValueError(f"{name}: expected at least one modality, got {value!r}")
    return names


def _floors(name: str, value: Any) -> tuple[tuple[str, float], ...]:
    if isinstance(value, Mapping):
        value = list(value.items())
    if not isinstance(value, list | tuple) or not all(
            isinstance(p, list | tuple) and len(p) == 2 for p in value):
        raise ValueError(f"{name}: expected a mapping modality -> floor (e.g. {{arm: 0.02}}), "
                         f"got {value!r}")
    if not all(isinstance(m, str) and m.strip() for m, _ in value):
        raise ValueError(f"{name}: expected modality names as keys, got {value!r}")
    check = _bounded("noise_floors")
    return tuple((m, check(f"{name}[{m!r}]", f)) for m, f in value)


#: Every option a grid may set, with the function that checks and converts a value.
OPTIONS: dict[str, Callable[[str, Any], Any]] = {
    **{key: _bounded(key) for key in ("n_basis", "regularizer", "noise_scale", "noise_floor",
                                      "signal_floor", "n_candidates", "refine_steps",
                                      "blend_rate", "blend_delay", "end_prob", "subsample",
                                      "dow_t", "ratio")},
    "noise_floors": _floors,
    "settle_tol": _optional("settle_tol"),
    "arrive_tol": _optional("arrive_tol"),
    "jitter_floor": _optional("jitter_floor"),
    "shrinkage": _choice(SHRINKAGE),
    "likelihood": _choice(LIKELIHOODS),
    "window_mode": _choice(WINDOW_MODES),
    "until_end": _flag,
    "observe": _modalities,
}
KNOWN = tuple(sorted(set(OPTIONS) | set(ALIASES)))


def read_grid(path: str | Path) -> list[dict[str, Any]]:
    """The points of a grid file, each a mapping of option to a checked value.

    Parameters
    ----------
    path : str or Path
        A ``.yaml``, ``.yml`` or ``.json`` file (see the module docstring).

    Returns
    -------
    list of dict
        One mapping per point, options under their :class:`EvalConfig` names
        (``window`` becomes ``window_mode``), repeated points dropped.

    Raises
    ------
    ValueError
        The file is missing or unreadable, an option is unknown, a list is empty,
        or a value is not what its option takes; the message names the option.
    """
    from sandbox.validation import is_file, read_mapping

    path = Path(path)
    if not is_file(path):
        raise ValueError(f"--grid: expected an existing .yaml, .yml or .json file, "
                         f"got {str(path)!r}")
    try:
        return parse_grid(read_mapping(path, "grid"))
    except ValueError as error:
        raise ValueError(f"grid {path}: {error}") from None


def parse_grid(data: Any) -> list[dict[str, Any]]:
    """The points of a parsed grid (see :func:`read_grid`)."""
    if not isinstance(data, Mapping) or not data:
        raise ValueError(f"expected a mapping of options to lists of values, or 'points:', "
                         f"got {_show(data)}")
    if "points" in data:
        if len(data) > 1:
            raise ValueError(f"expected 'points:' alone or lists of values, got 'points' and "
                             f"{sorted(str(k) for k in data if k != 'points')}")
        points = _listed(data["points"], "points")
        _count(len(points))
        if not all(isinstance(p, Mapping) for p in points):
            raise ValueError(f"points: expected a list of mappings option -> value, "
                             f"got {_show(points)}")
        return _unique([_point(p, f"points[{i}]") for i, p in enumerate(points)])
    for name in data:
        _known(name, str(name))
    lists = {name: _listed(values, str(name)) for name, values in data.items()}
    _count(prod(len(values) for values in lists.values()))
    checked = {ALIASES.get(name, name): [_value(name, str(name), v) for v in values]
               for name, values in lists.items()}
    if len(checked) < len(lists):
        raise ValueError("window: 'window_mode' is given twice (window is window_mode)")
    return _unique([dict(zip(checked, combo)) for combo in itertools.product(*checked.values())])


def _count(n: int) -> None:
    """Refuse a grid of more than ``MAX_GRID_POINTS`` points (counted, not expanded)."""
    if n > MAX_GRID_POINTS:
        raise ValueError(f"expected at most {MAX_GRID_POINTS} points "
                         f"(sandbox.limits.MAX_GRID_POINTS), got {n}")


def _known(name: Any, label: str) -> None:
    if not isinstance(name, str) or (name not in OPTIONS and name not in ALIASES):
        raise ValueError(f"{_show(label)}: unknown option; expected one of {list(KNOWN)}")


def _value(name: str, label: str, value: Any) -> Any:
    return OPTIONS[ALIASES.get(name, name)](label, value)


def _listed(values: Any, name: str) -> list:
    if not isinstance(values, list) or not values:
        raise ValueError(f"{_show(name)}: expected a non-empty list of values, "
                         f"got {_show(repr(values))}")
    return values


def _point(raw: Mapping, where: str) -> dict[str, Any]:
    point: dict[str, Any] = {}
    for name, value in raw.items():
        label = f"{where}.{name}"
        _known(name, label)
        field = ALIASES.get(name, name)
        if field in point:
            raise ValueError(f"{label}: {field!r} is given twice (window is window_mode)")
        point[field] = OPTIONS[field](label, value)
    return point


def _show(value: Any) -> str:
    """``value`` as one line of at most 80 characters: a printable name as is, anything else
    as its repr (a message never repeats a whole file, nor breaks a line)."""
    text = value if isinstance(value, str) and value.isprintable() and value else repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def _unique(points: list[dict]) -> list[dict]:
    out = []
    for p in points:
        if p not in out:
            out.append(p)
    return out


def config_for(point: Mapping[str, Any], base: EvalConfig | None = None) -> EvalConfig:
    """The configuration a point describes: ``base`` with the point's options.

    The dynamic formulation is evaluated at the point's ``dow_t`` only and the
    static one at its ``ratio`` only (the defaults of :func:`~sandbox.eval.tune.tune`
    when absent), as tuning does. Model options are checked by building the model.
    """
    options = dict(point)
    window = options.pop("dow_t", WINDOW)
    ratio = options.pop("ratio", RATIO)
    config = replace(base or EvalConfig(), windows=(window,), ratios=(ratio,), **options)
    config.model()
    return config


def label(point: Mapping[str, Any]) -> str:
    """Short text of a point: ``n_basis=15, likelihood=joint``."""
    def text(value):
        if isinstance(value, tuple):
            return ",".join(f"{v[0]}:{v[1]:g}" if isinstance(v, tuple) else str(v)
                            for v in value)
        return f"{value:g}" if isinstance(value, float) else str(value)

    return ", ".join(f"{k}={text(v)}" for k, v in point.items()) or "base"
