"""Documented limits of the recorded-data loader, checked before anything grows.

A recorded handover is a few seconds of about 100 rows per second, each cell a
short number. A file far outside that is refused as a skipped trial with its
reason instead of being read into memory (issue 13, findings 1, 2 and 7):

=============================  =============  ============================================
limit                          value          why
=============================  =============  ============================================
:data:`MAX_FILE_BYTES`         256 MiB        the recordings are about 100 kB per trial
:data:`MAX_ROWS_PER_FILE`      200,000        a minute (``MAX_DURATION_S``) at 3.3 kHz
:data:`MAX_FIELD_BYTES`        128 KiB        the ``csv`` module's own default field limit;
                                              a longer field is a stray quote
:data:`MAX_LINE_BYTES`         1 MiB          a recorded line is about 400 bytes
:data:`MAX_DURATION_S`         60 s           :mod:`sandbox.core.limits` (a trial's span)
:data:`MIN_MEDIAN_DT_S`        0.1 ms         :mod:`sandbox.core.limits` (time unit check)
:data:`MAX_ABS_VALUE`          1e6            no metre, radian or raw EMG value comes near
:data:`JOINT_LIMIT_TOL_RAD`    0.05 rad       robot joints may exceed the URDF limits by this
:data:`MAX_RATE_HZ`            10 kHz         ``resample_uniform``: 1 / ``MIN_MEDIAN_DT_S``
:data:`MAX_GRID_SAMPLES`       1,000,000      ``resample_uniform``: points of one grid
=============================  =============  ============================================

A trial whose time stamps span more than ``MAX_DURATION_S`` or whose median
sample interval is below ``MIN_MEDIAN_DT_S`` is skipped with a hint at the
unit the times look like (milliseconds, microseconds, nanoseconds). Robot
columns named after a joint of Baxter's URDF (``left_s0`` ... ``right_w2``)
must lie within that joint's limits widened by ``JOINT_LIMIT_TOL_RAD`` (the
recordings reach 0.011 rad past ``left_w1``'s upper limit, encoder noise).
"""

from __future__ import annotations

import functools

import numpy as np

from sandbox.core.limits import MAX_DURATION_S, MIN_MEDIAN_DT_S, check_duration

#: Largest trial file read (bytes).
MAX_FILE_BYTES = 256 * 2**20
#: Most data rows read from one trial file.
MAX_ROWS_PER_FILE = 200_000
#: Longest CSV field accepted (bytes; characters of the decoded text).
MAX_FIELD_BYTES = 128 * 2**10
#: Longest line of a trial file (characters): bounds the fields of one row.
MAX_LINE_BYTES = 2**20
#: Largest magnitude of a human or robot value (m, rad, raw EMG units).
MAX_ABS_VALUE = 1e6
#: How far (rad) a robot joint may go past its URDF limit before the trial is refused.
JOINT_LIMIT_TOL_RAD = 0.05
#: Highest rate (Hz) a demonstration is resampled at.
MAX_RATE_HZ = 1.0 / MIN_MEDIAN_DT_S
#: Most points of one resampling grid.
MAX_GRID_SAMPLES = 1_000_000

__all__ = [
    "JOINT_LIMIT_TOL_RAD",
    "MAX_ABS_VALUE",
    "MAX_GRID_SAMPLES",
    "MAX_RATE_HZ",
    "MAX_DURATION_S",
    "MAX_FIELD_BYTES",
    "MAX_FILE_BYTES",
    "MAX_LINE_BYTES",
    "MAX_ROWS_PER_FILE",
    "MIN_MEDIAN_DT_S",
    "check_duration",
    "joint_limits",
]


@functools.cache
def _baxter_limits() -> dict[str, tuple[float, float]]:
    """Joint name -> (lower, upper) position limits (rad) of Baxter's URDF (finite ones)."""
    from sandbox.robot.assets import source_urdf_path
    from sandbox.robot.urdf import read_joints

    joints = read_joints(source_urdf_path()).values()
    return {j.name: (float(j.lower), float(j.upper)) for j in joints
            if np.isfinite(j.lower) and np.isfinite(j.upper)}


def joint_limits(names: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper limits (rad) of robot columns ``names``; +/-inf where not a Baxter joint.

    Parameters
    ----------
    names : tuple of str
        Robot column names, e.g. ``("left_s0", ..., "left_w2")``.

    Returns
    -------
    lower, upper : ndarray, shape (len(names),)
        The URDF limits of the columns named after a joint of Baxter's URDF,
        ``-inf``/``inf`` for the others (their values are only bounded by
        :data:`MAX_ABS_VALUE`). If the robot description cannot be read, every
        column is unbounded.
    """
    try:
        limits = _baxter_limits()
    except (OSError, ValueError, ImportError):  # no robot description: nothing to compare with
        limits = {}
    lower = np.array([limits.get(n, (-np.inf, np.inf))[0] for n in names])
    upper = np.array([limits.get(n, (-np.inf, np.inf))[1] for n in names])
    return lower, upper
