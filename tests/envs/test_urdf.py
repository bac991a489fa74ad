"""The scene models: they load, have the documented masses and sizes, and ship in the wheel."""

from __future__ import annotations

import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

from sandbox import urdf
from sandbox.envs.pybullet import Simulation

REPO = Path(__file__).resolve().parents[2]
#: Documented mass (kg) and bounding box (m, x y z as loaded) of every object.
OBJECTS = {
    "box": (0.25, (0.085, 0.21, 0.045)),
    "glasses_case": (0.12, (0.065, 0.16, 0.04)),
    "tape": (0.22, (0.10, 0.048, 0.10)),
    "measuring_tape": (0.30, (0.075, 0.04, 0.075)),
    "screwdriver": (0.09, (0.20, 0.03, 0.03)),
}


@pytest.fixture(scope="module")
def sim():
    sim = Simulation()
    for i, name in enumerate(urdf.MODELS):
        sim.load_urdf(name, urdf.path(name), (3.0 * i, 0.0, 0.0))  # never stepped
    yield sim
    sim.close()


def test_every_model_resolves_and_loads(sim):
    assert set(urdf.OBJECTS) <= set(urdf.MODELS)
    for name in urdf.MODELS:
        assert urdf.path(name).is_file() and urdf.path(name).is_absolute()
        assert name in sim.bodies


@pytest.mark.parametrize("name", list(OBJECTS))
def test_object_mass_and_size(sim, name):
    mass, size = OBJECTS[name]
    body = sim.bodies[name]
    assert sim.client.getDynamicsInfo(body, -1)[0] == pytest.approx(mass)
    low, high = sim.client.getAABB(body, -1)
    # PyBullet pads bounding boxes by a small collision margin
    np.testing.assert_allclose(np.subtract(high, low), size, atol=0.01)


def test_base_pose_is_the_urdf_origin(sim):
    for i, name in enumerate(urdf.MODELS):
        np.testing.assert_allclose(sim.pose(name)[0], (3.0 * i, 0.0, 0.0), atol=1e-9)


def test_table_top_is_at_its_origin(sim):
    low, high = sim.client.getAABB(sim.bodies["table"], -1)
    origin, _ = sim.pose("table")
    assert high[2] - origin[2] == pytest.approx(0.0, abs=0.01)
    assert high[2] - low[2] == pytest.approx(0.74, abs=0.02)


def test_screwdriver_grasp_point_is_inside_its_handle(sim):
    low, high = sim.client.getAABB(sim.bodies["screwdriver"], -1)
    origin, _ = sim.pose("screwdriver")
    assert origin[0] - low[0] == pytest.approx(0.0833, abs=0.005)  # handle end behind it
    assert high[0] - origin[0] == pytest.approx(0.1167, abs=0.005)


def test_unknown_model_is_refused():
    with pytest.raises(ValueError, match="expected one of"):
        urdf.path("piano")


@pytest.mark.slow
def test_models_ship_in_the_wheel_and_resolve_from_an_install(tmp_path):
    src = tmp_path / "src"
    src.mkdir()
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc", "*.egg-info")
    for name in ("sandbox", "envs", "urdf"):
        shutil.copytree(REPO / name, src / name, ignore=ignore)
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        shutil.copy(REPO / name, src / name)
    dist = tmp_path / "dist"
    pip = [sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(dist), str(src)]
    built = subprocess.run([*pip, "--no-build-isolation"], capture_output=True, text=True)
    if built.returncode != 0:  # no `wheel` in this environment: let pip build in isolation
        built = subprocess.run(pip, capture_output=True, text=True)
    if built.returncode != 0:
        pytest.skip(f"cannot build a wheel here: {built.stderr.strip()[-300:]}")
    (wheel,) = dist.glob("*.whl")
    names = set(zipfile.ZipFile(wheel).namelist())
    for model in urdf.MODELS:
        assert f"sandbox/urdf/{model}.urdf" in names
    assert "sandbox/envs/handover.py" in names
    site = tmp_path / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "-q", "--target",
                    str(site), str(wheel)], check=True, capture_output=True)
    code = ("import sandbox.urdf as u; p = u.path('screwdriver'); "
            "print(p, p.read_text()[:5])")
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                         text=True, env={"PYTHONPATH": str(site), "PATH": ""}, check=True)
    assert out.stdout.startswith(str(site / "sandbox" / "urdf" / "screwdriver.urdf"))
    assert "<?xml" in out.stdout
