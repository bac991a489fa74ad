"""Other methods beside the Interaction ProMPs, behind the same predictor interface.

Every method here is a :class:`~sandbox.methods.base.MethodPredictor`: fed
observations (``observe(t, y)``), updated every ``dow_t`` seconds, asked for
the robot command (``command(t)``) and the task posterior, exactly like
:class:`~sandbox.core.DynamicPredictor`, whose observation stream, plan and
blending it reuses. They learn from a :class:`DemoLibrary`: the IProMP model
fitted on the training demos and those demos' weights.

===========  ==============================================================
name         method
===========  ==============================================================
``bip``      :mod:`~sandbox.methods.bip`: Bayesian Interaction Primitives, an
             EKF over phase, phase velocity and all weights (Campbell & Ben
             Amor 2017)
``ebip``     :mod:`~sandbox.methods.ebip`: ensemble BIP, an ensemble Kalman
             filter seeded with the demos (Campbell, Stepputtis & Ben Amor 2019)
``dtw``      :mod:`~sandbox.methods.dtw`: open-end DTW against every demo
``nearest``  :mod:`~sandbox.methods.nearest`: the nearest demo at its own timing
===========  ==============================================================

:func:`make_predictor` builds any of :data:`METHODS`, the IProMP's
``dynamic`` and ``static`` included. numpy/scipy only, like the core.
"""

from __future__ import annotations

from sandbox.methods.base import MethodPredictor, PhasePrediction
from sandbox.methods.bip import BIPPredictor
from sandbox.methods.dtw import DTWPredictor
from sandbox.methods.ebip import EBIPPredictor
from sandbox.methods.library import DemoLibrary
from sandbox.methods.nearest import NearestPredictor

__all__ = ["METHODS", "OTHER_METHODS", "BIPPredictor", "DTWPredictor", "DemoLibrary",
           "EBIPPredictor", "MethodPredictor", "NearestPredictor", "PhasePrediction",
           "check_methods", "check_observable", "make_predictor"]

#: The methods of this package, by name.
OTHER_METHODS = {"bip": BIPPredictor, "ebip": EBIPPredictor, "dtw": DTWPredictor,
                 "nearest": NearestPredictor}
#: Every method a comparison runs: the IProMP's two formulations and the others.
METHODS = ("dynamic", "static", *OTHER_METHODS)
#: Modality kinds each method can observe (all of them handle positions and signals).
OBSERVABLE_KINDS = {name: ("position", "signal") for name in METHODS}


def check_methods(names, option: str = "methods") -> tuple[str, ...]:
    """Distinct names among :data:`METHODS` (a list or ``"a,b"``); one-line ``ValueError`` else."""
    if isinstance(names, str):
        names = [n.strip() for n in names.split(",") if n.strip()]
    names = tuple(names)
    unknown = [n for n in names if n not in METHODS]
    if not names or unknown or len(set(names)) != len(names):
        raise ValueError(f"{option}: expected distinct names among {', '.join(METHODS)}, "
                         f"got {','.join(map(str, names)) or 'none'}"
                         + (f" (unknown: {', '.join(map(str, unknown))})" if unknown else ""))
    return names


def check_observable(methods, modalities, option: str = "observe", *,
                     kinds: dict | None = None) -> None:
    """Every method can observe every modality (a ``Modality`` with ``name`` and ``kind``);
    a one-line ``ValueError`` naming what a method observes otherwise. ``kinds`` maps a
    method to the kinds it observes (default :data:`OBSERVABLE_KINDS`)."""
    table = OBSERVABLE_KINDS if kinds is None else kinds
    for name in methods:
        kinds_of = table[name]
        for m in modalities:
            if m.kind not in kinds_of:
                raise ValueError(f"{option}: method {name!r} cannot observe {m.name!r} (a "
                                 f"{m.kind} modality); it observes {', '.join(kinds_of)} "
                                 f"modalities")


def make_predictor(name: str, library: DemoLibrary, *, dow_t: float = 0.2, ratio: float = 0.5,
                   expected_duration: float | None = None, **options):
    """The predictor of method ``name`` on ``library``'s model and demos.

    Parameters
    ----------
    name : str
        One of :data:`METHODS`.
    library : DemoLibrary
    dow_t : float
        Seconds between updates (all but ``static``).
    ratio, expected_duration
        Of :class:`~sandbox.core.StaticPredictor` (``static`` only).
    **options
        Predictor options (``subsample``, ``observe``, blending, the method's own).
    """
    from sandbox.core import DynamicPredictor, StaticPredictor

    check_methods([name], "method")
    if name == "dynamic":
        return DynamicPredictor(library.model, dow_t=dow_t, **options)
    if name == "static":
        return StaticPredictor(library.model, ratio=ratio, expected_duration=expected_duration,
                               **options)
    return OTHER_METHODS[name](library, dow_t, **options)
