"""Any arm's robot files: the registry's URDFs as the sandbox loads them, written to the cache.

Like Baxter's (:mod:`sandbox.robot.assets`), every arm's URDF comes from the
installed ``example-robot-data``; its ``package://`` mesh paths are made
absolute and the sandbox's gripper changes applied
(:mod:`sandbox.robot.arms`), in a copy in the per-user cache. Nothing is
copied into the repository and nothing is downloaded.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.metadata
from pathlib import Path

from sandbox.robot.arms import SIMPLE_GRIPPER, arm_spec
from sandbox.robot.assets import (
    DISTRIBUTION,
    _write_atomic,
    baxter_description_dir,
    cache_dir,
    rewritten_urdf_text,
    urdf_path,
)
from sandbox.robot.urdf import UrdfVisual, read_visuals

SHARE_SUBDIR = "cmeel.prefix/share/example-robot-data"
PACKAGE_ROOT = "package://example-robot-data/"


def share_dir() -> Path:
    """Folder ``share/example-robot-data`` of the installed distribution (holds ``robots/``)."""
    return baxter_description_dir().parents[1]


def arm_text(name: str) -> str:
    """Text of robot ``name``'s URDF as the sandbox loads it (:mod:`sandbox.robot.arms`).

    Mesh paths are made absolute; an arm without a gripper in the package gets
    :data:`~sandbox.robot.arms.SIMPLE_GRIPPER` on its flange (``tool0``); finger joints the
    package declares fixed but the arm closes become revolute. Baxter's is
    :func:`rewritten_urdf_text`.
    """
    spec = arm_spec(name)
    if name == "baxter":
        return rewritten_urdf_text()
    text = (share_dir() / "robots" / spec.urdf).read_text(encoding="utf-8")
    text = text.replace(PACKAGE_ROOT, share_dir().as_posix() + "/")
    for joint in spec.revolute_fingers:
        fixed = f'<joint name="{joint}" type="fixed">'
        if fixed not in text:
            raise ValueError(f"{spec.urdf}: expected a fixed joint {joint!r} to make revolute")
        text = text.replace(fixed, f'<joint name="{joint}" type="revolute">')
    if spec.gripper_added:
        end = text.rindex("</robot>")
        text = text[:end] + SIMPLE_GRIPPER.format(flange="tool0", rpy="0 0 0") + text[end:]
    return text


def arm_urdf_path(name: str) -> Path:
    """Path of robot ``name``'s URDF (:func:`arm_text`), written to the cache if needed.

    Returns
    -------
    pathlib.Path
        ``<cache_dir>/<name>-<version>-<hash>.urdf`` (Baxter: :func:`urdf_path`).
    """
    if name == "baxter":
        return urdf_path()
    path = _checked_arm_path(name, str(share_dir()))
    if not path.is_file():
        _write_atomic(path, arm_text(name))
    return path


@functools.cache
def _checked_arm_path(name: str, share: str) -> Path:
    version = importlib.metadata.version(DISTRIBUTION)
    text = arm_text(name)
    digest = hashlib.sha1((share + text).encode()).hexdigest()[:10]
    path = cache_dir() / f"{name}-{version}-{digest}.urdf"
    if not path.is_file() or path.read_text(encoding="utf-8") != text:
        _write_atomic(path, text)
    return path


def arm_visuals(name: str) -> list[UrdfVisual]:
    """Visual geometries of robot ``name`` (mesh file names absolute)."""
    return read_visuals(arm_urdf_path(name))
