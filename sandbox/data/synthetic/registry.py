"""The registry of synthetic datasets: :func:`make_dataset` by name."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from sandbox.data.demonstration import Demonstration
from sandbox.data.synthetic.families import diverging_demos, objects_demos
from sandbox.data.synthetic.observe import check_observe
from sandbox.data.synthetic.session import Session, as_session
from sandbox.data.synthetic.two_task import two_task_demos

_GENERATORS: dict[str, Callable[..., list[Demonstration]]] = {
    "two_task": two_task_demos,
    "diverging": diverging_demos,
    "objects": objects_demos,
}

#: Names accepted by :func:`make_dataset`.
DATASETS = tuple(_GENERATORS)


def make_dataset(
    name: str,
    n_per_task: int,
    rng: np.random.Generator,
    *,
    observe: Sequence[str] | str = ("hand",),
    session: Session | int | None = None,
    **options: Any,
) -> list[Demonstration]:
    """Generate a named synthetic dataset of paired human/robot demonstrations.

    Parameters
    ----------
    name : str
        One of :data:`DATASETS`: ``"two_task"`` (:func:`two_task_demos`, no
        inverse kinematics, fastest), ``"diverging"`` (:func:`diverging_demos`,
        Experiment 2) or ``"objects"`` (:func:`objects_demos`, Experiment 1).
    n_per_task : int
        Demonstrations per task.
    rng : numpy.random.Generator
        Source of randomness; the same seed gives the same demonstrations.
    observe : str or sequence of str
        Observed modalities: ``"hand"`` (default), ``"hand,arm"`` (``human``
        has 9 columns: the hand, then the elbow and the shoulder) or ``"arm"``.
        The hand is the same with or without the arm.
    session : Session or int, optional
        A recording session (:mod:`sandbox.data.synthetic.session`: tracker
        frame, where the fingertip meets the hand, tempo, the motion's tail);
        an integer >= 0 is :func:`~sandbox.data.synthetic.session.draw_session`
        of it. None (default): today's data, bit for bit. ``"two_task"`` has
        no robot kinematics and takes None only.
    **options
        Keyword options of the dataset's generator.

    Returns
    -------
    list of Demonstration
        The demonstrations, grouped by task.
    """
    if name not in _GENERATORS:
        raise ValueError(f"name: expected one of {list(DATASETS)}, got {name!r}")
    observe, session = check_observe(observe), as_session(session)
    if session is None:
        return _GENERATORS[name](n_per_task, rng, observe=observe, **options)
    if name == "two_task":
        raise ValueError("session: expected None for 'two_task' (its robot is no arm meeting "
                         "the hand); use 'objects' or 'diverging' for sessions")
    return _GENERATORS[name](n_per_task, rng, observe=observe, session=session, **options)
