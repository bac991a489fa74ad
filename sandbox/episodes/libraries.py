"""The training demos of the models the episodes fit, for the methods that learn from them.

:class:`~sandbox.episodes.method_policy.MethodPolicy` drives BIP, eBIP, DTW and
nearest-neighbour (:mod:`sandbox.methods`) from a model; those methods need the
demos the model was fitted on (:class:`~sandbox.methods.DemoLibrary`). Where the
episodes fit a model (synthetic families and sessions, recorded replays) they
keep its demos here, by model, for as long as the model lives; the library is
made when a method first asks for it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING
from weakref import WeakKeyDictionary

if TYPE_CHECKING:
    from sandbox.core import IProMP

#: The demos each model was fitted on, then its library once a method asked for it.
_KEPT: WeakKeyDictionary = WeakKeyDictionary()


def remember_demos(model: IProMP, demos) -> IProMP:
    """Keep ``demos`` (those ``model`` was fitted on) for :func:`library_of`; returns ``model``."""
    _KEPT[model] = list(demos)
    return model


def library_of(model: IProMP):
    """The :class:`~sandbox.methods.DemoLibrary` of ``model``: its demos if they were kept
    (:func:`remember_demos`), else moment-matched stand-ins
    (:meth:`~sandbox.methods.DemoLibrary.from_model`: exact for BIP's prior, an
    approximation of the demos for eBIP, DTW and nearest)."""
    from sandbox.methods import DemoLibrary

    kept = _KEPT.get(model)
    if kept is None:
        return DemoLibrary.from_model(model)
    if not isinstance(kept, DemoLibrary):
        kept = _KEPT[model] = DemoLibrary.from_demos(model, kept)
    return kept
