"""Arguments of the handover environment's constructor, checked before anything is made.

Each ``check_*`` returns the argument as the environment uses it or raises a
``ValueError`` that names the argument and says what was expected (issue 13:
a wrong type is never a ``TypeError`` later, at ``reset``).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from sandbox.envs.task import RewardWeights
from sandbox.limits import BOUNDS
from sandbox.validation import check_array, check_integer, check_number, check_positive

#: Arguments of :class:`sandbox.viz.Viewer` accepted in ``viewer_options`` ("human" mode).
VIEWER_KEYS = ("fps", "record", "resolution", "camera", "target", "fov", "floor_z", "realtime",
               "open_browser", "host")
#: Lowest and highest control rate (Hz): ``control_hz`` of the one table of limits.
MIN_CONTROL_HZ = BOUNDS["control_hz"].low
MAX_CONTROL_HZ = BOUNDS["control_hz"].high
#: Most physics steps per control step accepted.
MAX_SUBSTEPS = 100


def check_control_hz(value: Any) -> float:
    """``control_hz`` in [MIN_CONTROL_HZ, MAX_CONTROL_HZ] (:data:`sandbox.limits.BOUNDS`)."""
    return float(BOUNDS["control_hz"].check(value, "control_hz"))


def check_substeps(value: Any) -> int:
    """``substeps``: an integer from 1 to :data:`MAX_SUBSTEPS`."""
    return check_integer(value, "substeps", 1, MAX_SUBSTEPS)


def check_reward_weights(value: Any) -> RewardWeights:
    """``reward_weights`` as given: None (the defaults), a RewardWeights or a dict of its fields."""
    if value is None:
        return RewardWeights()
    if isinstance(value, RewardWeights):
        return value
    if isinstance(value, Mapping):
        fields = ("distance", "success", "action_rate")
        unknown = sorted(map(str, set(value) - set(fields)))
        if unknown:
            raise ValueError(f"reward_weights: expected keys among {list(fields)}, got {unknown}")
        return RewardWeights(**value)
    raise ValueError(f"reward_weights: expected a RewardWeights or a dict of its fields, "
                     f"got {type(value).__name__}")


def check_viewer_options(options: Any) -> dict[str, Any]:
    """Check ``viewer_options`` (keys and the type of each value) before anything starts."""
    if options is None:
        return {}
    if not isinstance(options, Mapping):
        raise ValueError(f"viewer_options: expected a dict of Viewer arguments, "
                         f"got {type(options).__name__}")
    unknown = sorted(map(str, set(options) - set(VIEWER_KEYS)))
    if unknown:
        raise ValueError(f"viewer_options: expected keys among {list(VIEWER_KEYS)}, "
                         f"got {unknown}")
    out = dict(options)
    for key in ("record", "realtime", "open_browser"):
        if key in out and not isinstance(out[key], bool):
            raise ValueError(f"viewer_options[{key!r}]: expected True or False, got {out[key]!r}")
    for key in ("fps", "fov"):
        if key in out:
            check_positive(out[key], f"viewer_options[{key!r}]")
    if out.get("resolution") is not None:
        check_positive(out["resolution"], "viewer_options['resolution']")
    if out.get("floor_z") is not None:
        check_number(out["floor_z"], "viewer_options['floor_z']")
    for key in ("camera", "target"):
        if key in out:
            check_array(out[key], f"viewer_options[{key!r}]", 1, shape=(3,))
    if "host" in out and (not isinstance(out["host"], str) or not out["host"]):
        raise ValueError(f"viewer_options['host']: expected an address such as '127.0.0.1', "
                         f"got {out['host']!r}")
    return out
