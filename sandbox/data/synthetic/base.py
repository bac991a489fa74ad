"""Constants and small helpers shared by the synthetic generators.

The numbers marked *measured* come from the recorded BIRL handovers
(``birl-handover-20180329``, 174 trials, pooled over its four tasks).
"""

from __future__ import annotations

import numpy as np

from sandbox.robot import ARM_JOINTS
from sandbox.validation import FloatArray

HUMAN_NAMES = ("human_left_hand_x", "human_left_hand_y", "human_left_hand_z")
#: The robot's columns: the recordings name them after the URDF's left-arm joints.
ROBOT_NAMES = ARM_JOINTS
#: Mean start of the human left hand in Baxter's base frame in the recordings (m).
HAND_START = np.array([1.10, -0.12, 0.25])


def minimum_jerk(s: np.ndarray) -> np.ndarray:
    """Minimum-jerk time scaling 10s^3 - 15s^4 + 6s^5 of a phase ``s`` in [0, 1]."""
    s = np.clip(s, 0.0, 1.0)
    return s**3 * (10.0 - 15.0 * s + 6.0 * s**2)


def skewed_minimum_jerk(s: np.ndarray, skew: float = 1.0) -> np.ndarray:
    """Minimum-jerk scaling of the warped phase ``s**skew``.

    ``skew < 1`` moves the speed peak earlier (a human reach accelerates faster
    than it decelerates: the recorded peak is at ~40 % of the reach), ``skew = 1``
    is the symmetric profile. Stays monotonic from 0 to 1 for ``skew > 1/3``.

    Parameters
    ----------
    s : array_like, shape (T,)
        Phase of the motion; clipped to [0, 1].
    skew : float
        Warp exponent (> 1/3).

    Returns
    -------
    ndarray, shape (T,)
        Progress in [0, 1].
    """
    s = np.clip(np.asarray(s, dtype=float), 0.0, 1.0)
    return minimum_jerk(s**skew)


def child_rng(rng: np.random.Generator) -> np.random.Generator:
    """An independent generator spawned from ``rng``'s seed sequence.

    ``rng``'s stream is untouched (its next draws are the same as without this
    call); only its seed sequence's spawn counter advances, so two calls give
    two different children (``Generator.spawn``, or its equivalent before
    numpy 1.25).
    """
    if hasattr(rng, "spawn"):
        return rng.spawn(1)[0]
    return np.random.default_rng(rng.bit_generator._seed_seq.spawn(1)[0])  # pragma: no cover


def sample_times(duration: float, rate_hz: float) -> FloatArray:
    """Row times (s) from 0 to ``duration`` at ``rate_hz``, last row exactly at ``duration``.

    Returns
    -------
    ndarray, shape (T,)
        Strictly increasing times.
    """
    t = np.arange(0.0, duration + 0.5 / rate_hz, 1.0 / rate_hz)
    t[-1] = duration  # arange stops within half a row of it, so order is kept
    return t
