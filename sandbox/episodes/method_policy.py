"""The other methods (:mod:`sandbox.methods`: BIP, eBIP, DTW, nearest) as controllers."""

from __future__ import annotations

from sandbox.core import IProMP
from sandbox.episodes.policies import CLOSED_LOOP, IProMPPolicy


class MethodPolicy(IProMPPolicy):
    """Another method (:mod:`sandbox.methods`: ``bip``, ``ebip``, ``dtw``, ``nearest``) as a
    controller: fed, updated and followed exactly as :class:`IProMPPolicy`.

    Parameters
    ----------
    model : IProMP
        A fitted model; the method learns from its demos
        (:func:`~sandbox.episodes.libraries.library_of`).
    method : str
        One of :data:`sandbox.methods.OTHER_METHODS`.
    dow_t, control_hz, close_radius, max_velocity, observe, robot, **options
        As for :class:`IProMPPolicy` (``options`` may hold the method's own).
    """

    def __init__(self, model: IProMP, method: str, *, dow_t: float = 0.2,
                 control_hz: float = 50.0, close_radius: float = 0.045, max_velocity=None,
                 observe=None, robot: str = "baxter", **options) -> None:
        from sandbox.methods import OTHER_METHODS, make_predictor

        if method not in OTHER_METHODS:
            raise ValueError(f"method: expected one of {', '.join(OTHER_METHODS)}, "
                             f"got {method!r}")
        self._setup(model, observe, control_hz, close_radius, max_velocity, robot)
        from sandbox.episodes.libraries import library_of

        self.predictor = make_predictor(method, library_of(model), dow_t=dow_t,
                                        subsample=self.subsample, observe=self.observe,
                                        **{**CLOSED_LOOP, **options})
        self.reset()
