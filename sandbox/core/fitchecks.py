"""Checks of the options and per-demo parts an :class:`~sandbox.core.model.IProMP` fit takes.

Noise floors and tolerances within :mod:`sandbox.limits`, floors named after the
demonstrations' modalities, per-demo fits (:class:`~sandbox.core.fitting.DemoFit`) of
one layout, and the robot dims' space. Each raises a one-line ``ValueError``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from sandbox.core.fitting import DemoFit
from sandbox.core.limits import MAX_ABS_VALUE, MIN_NOISE_STD
from sandbox.core.modality import Modality
from sandbox.limits import BOUNDS
from sandbox.validation import check_positive


def check_floor(value, name: str, bound: str | None = None) -> float:
    """A noise floor: a number in [MIN_NOISE_STD, the high end of ``BOUNDS[bound]``]
    (:mod:`sandbox.limits`; ``MAX_ABS_VALUE`` without ``bound``)."""
    v = check_positive(value, name, high=MAX_ABS_VALUE if bound is None else BOUNDS[bound].high)
    if v < MIN_NOISE_STD:
        raise ValueError(f"{name}: expected at least {MIN_NOISE_STD:g} (limits.MIN_NOISE_STD), "
                         f"got {value!r}")
    return v


def check_tolerance(value, name: str) -> float | None:
    """``settle_tol``/``arrive_tol``: None, or a number in the range ``BOUNDS[name]``."""
    return None if value is None else check_positive(value, name, high=BOUNDS[name].high)


def check_floor_names(floors: Mapping[str, float], modalities: Sequence[Modality]) -> None:
    """Refuse floors of modalities the demonstrations do not have (``ValueError``)."""
    unknown = sorted(set(floors) - {m.name for m in modalities})
    if unknown:
        raise ValueError(f"noise_floors: expected floors of the demonstrations' modalities "
                         f"{[m.name for m in modalities]}, got {unknown}")


def check_fits(fits, n_basis: int) -> None:
    """Per-demo fits of one layout: DemoFit instances with one P and one D*N."""
    if isinstance(fits, (str, bytes)) or not hasattr(fits, "__len__") or len(fits) == 0:
        raise ValueError("fits: expected a non-empty sequence of DemoFit")
    if not all(isinstance(f, DemoFit) for f in fits):
        raise ValueError("fits: expected DemoFit instances (IProMP.demo_fit)")
    sizes = {(f.residual.size, f.weights.size) for f in fits}
    if len(sizes) != 1 or next(iter(sizes))[1] % n_basis:
        raise ValueError(f"fits: expected one layout (P, D*N with N={n_basis}), "
                         f"got {sorted(sizes)}")

def check_robot_space(value) -> str:
    """``"joint"`` or ``"task"``: what a demonstration's robot dims are (``ValueError`` else)."""
    if value not in ("joint", "task"):
        raise ValueError(f"robot_space: expected 'joint' or 'task', got {value!r}")
    return str(value)
