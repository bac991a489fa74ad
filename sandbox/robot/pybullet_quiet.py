"""PyBullet, imported without the line it prints on stderr.

``import pybullet`` writes "pybullet build time: ..." from C straight to file
descriptor 2, before every command that loads Baxter. Modules that need
PyBullet import it from here: the first import runs with descriptor 2 sent to
``/dev/null`` (best effort: a stderr without a descriptor is left alone), and
Python's own errors, raised after the descriptor is restored, still show.
"""

from __future__ import annotations

import os
import sys


def _import_quietly() -> None:
    try:
        fd = sys.stderr.fileno()
    except (AttributeError, OSError, ValueError):   # e.g. a replaced sys.stderr
        return
    sys.stderr.flush()
    saved = os.dup(fd)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), fd)
            import pybullet  # noqa: F401
            import pybullet_utils.bullet_client  # noqa: F401
    finally:
        os.dup2(saved, fd)
        os.close(saved)


if "pybullet" not in sys.modules:
    _import_quietly()

import pybullet  # noqa: E402  (already imported above, silently)
from pybullet_utils.bullet_client import BulletClient  # noqa: E402

__all__ = ["BulletClient", "pybullet"]
