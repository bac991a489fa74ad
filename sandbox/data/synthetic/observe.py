"""What a synthetic demonstration observes of the human: the hand, the arm, or both.

The hand is always generated (it drives everything else); the arm
(:mod:`sandbox.data.synthetic.arm`) only when observed, from its own random
stream, a child of the demonstration's tracker seed: hand-only datasets are
bit-identical with or without this module, and the hand of a hand-and-arm
dataset is the hand-only dataset's.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from sandbox.core.modality import Modality
from sandbox.data.spec import ARM, HAND
from sandbox.data.synthetic.arm import ArmModel, arm_positions, arm_rng
from sandbox.data.synthetic.tracker import TrackerModel, track_arm, track_hand
from sandbox.validation import FloatArray

#: The modalities a synthetic set can carry, by name.
SYNTHETIC_MODALITIES: dict[str, Modality] = {"hand": HAND, "arm": ARM}


def check_observe(observe: Sequence[str] | str) -> tuple[str, ...]:
    """Return the observed modality names, checked: distinct names from ``hand``, ``arm``.

    Parameters
    ----------
    observe : str or sequence of str
        ``"hand"``, ``"hand,arm"``, ``("arm",)``, ...; the columns follow this order.
    """
    names = observe.split(",") if isinstance(observe, str) else observe
    if not isinstance(names, Sequence):
        raise ValueError(f"observe: expected names like 'hand,arm', got {observe!r}")
    names = tuple(str(n).strip() for n in names if str(n).strip())
    if "emg" in names:
        raise ValueError(f"observe: EMG is not simulated: synthetic sets carry the hand only, "
                         f"or the hand and the arm (got {list(names)})")
    unknown = [n for n in names if n not in SYNTHETIC_MODALITIES]
    if not names or unknown or len(set(names)) != len(names):
        raise ValueError(f"observe: synthetic sets carry the hand and the arm; expected "
                         f"distinct names from {list(SYNTHETIC_MODALITIES)}, got {observe!r}")
    return names


def observe_human(
    observe: tuple[str, ...],
    times: FloatArray,
    clean: FloatArray,
    tracker: TrackerModel,
    seed: int,
    arm_model: ArmModel | None = None,
    frame: Callable[[FloatArray], FloatArray] | None = None,
) -> tuple[FloatArray, tuple[Modality, ...], dict[str, Any]]:
    """The tracked human of one demonstration, its modalities and extra ``meta``.

    Parameters
    ----------
    observe : tuple of str
        Checked names (:func:`check_observe`).
    times : ndarray, shape (T,)
        Row times (s).
    clean : ndarray, shape (T, 3)
        The clean hand (m).
    tracker : TrackerModel
        Tracker artefacts, shared by hand and arm.
    seed : int
        The demonstration's tracker seed: the hand's tracker uses
        ``default_rng(seed)``, the arm :func:`~sandbox.data.synthetic.arm.arm_rng`.
    arm_model : ArmModel, optional
        The arm (default ``ArmModel()``).
    frame : callable, optional
        Maps clean positions (T, 3k) m of Baxter's base frame to the tracker's
        frame (a session's :meth:`~sandbox.data.synthetic.session.Session.to_tracker`),
        applied before the artefacts; default: the tracker's frame is Baxter's.
        The arm itself is built from the true hand, ``clean_arm`` is the true arm.

    Returns
    -------
    human : ndarray, shape (T, P)
        The observed columns, modality after modality (P = 3 per hand, 6 per arm).
    modalities : tuple of Modality
        What they are.
    meta : dict
        ``{"clean_arm": (T, 6) m}`` when the arm is observed, else empty.
    """
    seen = (lambda x: x) if frame is None else frame
    hand, schedule = track_hand(times, seen(clean), tracker, np.random.default_rng(seed))
    columns, meta = {"hand": hand}, {}
    if "arm" in observe:
        rng = arm_rng(seed)
        meta["clean_arm"] = arm_positions(times, clean, rng, model=arm_model)
        columns["arm"] = track_arm(times, seen(meta["clean_arm"]), tracker, schedule, rng)
    human = np.column_stack([columns[name] for name in observe])
    return human, tuple(SYNTHETIC_MODALITIES[name] for name in observe), meta
