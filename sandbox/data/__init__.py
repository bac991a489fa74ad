"""Demonstrations: the container, recorded-data loading and synthetic handovers.

``load_recorded``, ``load_trial``, ``HandFilter`` and ``FilterConfig`` are imported on
first use, so ``import sandbox.data`` stays light (filterpy, and the scipy.stats it pulls
in, only once a :class:`HandFilter` is made).
"""

from sandbox.data.datasets import load_dataset, resample_uniform
from sandbox.data.demonstration import Demonstration, stack_tasks

_LAZY = {
    "load_recorded": "sandbox.data.recorded",
    "load_trial": "sandbox.data.recorded",
    "HandFilter": "sandbox.data.filtering",
    "FilterConfig": "sandbox.data.filtering",
}

__all__ = ["Demonstration", "load_dataset", "resample_uniform", "stack_tasks", *_LAZY]


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'sandbox.data' has no attribute {name!r}")
