"""The options a scenario file passes on: ``policy.options`` and ``model.options``.

Their names are the keyword parameters of what receives them (the policy, its
predictor and their base; :class:`~sandbox.core.IProMP`), read with
:mod:`inspect`, so a misspelt option is refused when the file is read, naming
the valid ones, instead of failing later inside a constructor. A value whose
name is an entry of :data:`sandbox.limits.BOUNDS` is checked against it.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any


def policy_options(kind: str) -> tuple[str, ...]:
    """Names ``policy.options`` may hold for a policy of ``kind``: the keyword parameters of
    the policy, its predictor and their base, but those the scenario sets itself."""
    from sandbox.core.predictor import DynamicPredictor, StaticPredictor
    from sandbox.core.updating import PredictorBase
    from sandbox.episodes.policies import IProMPPolicy, StaticPolicy

    policy, predictor = ((IProMPPolicy, DynamicPredictor) if kind == "dynamic"
                         else (StaticPolicy, StaticPredictor))
    names = set().union(*(keywords(f) for f in (policy.__init__, predictor.__init__,
                                                 PredictorBase.__init__)))
    return tuple(sorted(names - {"model", "dow_t", "ratio", "observe", "subsample"}))


def keywords(function) -> set[str]:
    """Names of the parameters of ``function`` that can be passed by keyword."""
    import inspect

    kinds = (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)
    return {n for n, p in inspect.signature(function).parameters.items()
            if p.kind in kinds and n != "self"}


def checked_options(check: Any, options: Mapping, key: str, allowed) -> dict:
    """``options`` after checking their names against ``allowed`` and, for a name of the
    one table of limits, the value against its range."""
    from sandbox.limits import BOUNDS

    options = check.keys(options, key, allowed)
    return {name: (check.bounded(value, f"{key}.{name}", name)
                   if name in BOUNDS and value is not None else value)
            for name, value in options.items()}
