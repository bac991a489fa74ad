"""Baxter's files located in the installed example-robot-data, URDF rewritten into a cache."""

from __future__ import annotations

import importlib.metadata
import re
import subprocess
import sys
from pathlib import Path

import pytest

from sandbox.robot import assets


@pytest.fixture()
def fresh_cache(tmp_path, monkeypatch):
    """A private cache folder, and the per-process caches cleared before and after."""
    monkeypatch.setenv("SANDBOX_CACHE", str(tmp_path))
    assets._checked_urdf_path.cache_clear()
    yield tmp_path
    assets._checked_urdf_path.cache_clear()
    assets.baxter_description_dir.cache_clear()


def _mesh_paths(text: str) -> list[str]:
    return re.findall(r'filename="([^"]+)"', text)


def test_description_dir_is_inside_the_distribution():
    folder = assets.baxter_description_dir()
    dist = importlib.metadata.distribution("example-robot-data")
    assert folder.is_absolute() and (folder / "urdf" / "baxter.urdf").is_file()
    assert str(folder).startswith(str(Path(dist.locate_file("")).resolve()))


def test_mesh_dir_holds_the_arm_meshes():
    meshes = assets.mesh_dir()
    for name in ("upper_shoulder/S0.DAE", "wrist/W2.DAE", "torso/base_link.DAE"):
        assert (meshes / name).is_file()


def test_rewritten_urdf_points_to_existing_meshes(fresh_cache):
    path = assets.urdf_path()
    text = path.read_text()
    assert path.parent == fresh_cache
    assert "package://" not in text
    meshes = _mesh_paths(text)
    assert len(meshes) > 20
    assert all(Path(m).is_absolute() and Path(m).is_file() for m in meshes)
    # Everything but the mesh paths is unchanged.
    source = assets.source_urdf_path().read_text()
    assert len(_mesh_paths(source)) == len(meshes)
    assert re.sub(r'filename="[^"]+"', "", source) == re.sub(r'filename="[^"]+"', "", text)


def test_urdf_path_is_deterministic_and_repaired_when_stale_or_missing(fresh_cache):
    first = assets.urdf_path()
    good = first.read_text()
    first.write_text("stale")
    assets._checked_urdf_path.cache_clear()  # a new process
    second = assets.urdf_path()
    assert second == first and second.read_text() == good
    second.unlink()
    assert assets.urdf_path().read_text() == good  # same process, file deleted meanwhile
    assert [p.name for p in fresh_cache.iterdir()] == [first.name]  # no temporary left over


def test_missing_package_gives_an_actionable_error(monkeypatch, fresh_cache):
    def missing(name):
        raise importlib.metadata.PackageNotFoundError(name)

    monkeypatch.setattr(importlib.metadata, "distribution", missing)
    assets.baxter_description_dir.cache_clear()
    with pytest.raises(FileNotFoundError, match="pip install 'example-robot-data>=6,<7'"):
        assets.baxter_description_dir()


def test_importing_the_robot_package_does_not_import_pybullet():
    code = (
        "import sys, sandbox.robot, numpy as np\n"
        "sandbox.robot.BaxterKinematics().fk(np.zeros(7))\n"
        "print(sorted(m for m in ('pybullet', 'meshcat', 'gymnasium') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
