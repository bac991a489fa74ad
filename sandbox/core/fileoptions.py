"""The options a model file stores beyond the format's first hyperparameters
(:func:`put_options`, called by :func:`sandbox.core.io.save_model`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from sandbox.core.model import IProMP


def put_options(model: IProMP, meta: dict) -> None:
    """Write the options older files lack into ``meta``: ``jitter_floor`` always (null too,
    so a file tells its constant floor from the default), the others only when set."""
    meta["hyperparameters"]["jitter_floor"] = getattr(model, "jitter_floor", None)  # null too
    meta["hyperparameters"]["span_reg"] = getattr(model, "span_reg", None)  # null too
    if getattr(model, "span_reg", None) is not None:
        meta["span_used"] = getattr(model, "span_report", {})
    if getattr(model, "noise_floor", None) == "auto":     # the floors it learned (m)
        meta["floors_used"] = np.asarray(model.floors_used, dtype=float).tolist()
    _put_condition(model, meta)
    if getattr(model, "post_end", None) is not None:     # posthold.py
        meta["hyperparameters"]["post_end"] = model.post_end
        meta["post_var"] = np.asarray(model.post_var, dtype=float).tolist()
    if getattr(model, "shrinkage", "none") != "none":
        meta["hyperparameters"]["shrinkage"] = model.shrinkage


def _put_condition(model, meta: dict) -> None:
    """A ``condition_floor``'s noise (:mod:`sandbox.core.condfloor`), if any, into ``meta``."""
    if getattr(model, "condition_noise", None) is not None:
        meta["hyperparameters"]["condition_floor"] = model.condition_floor
        meta["condition_noise"] = np.asarray(model.condition_noise, dtype=float).tolist()
