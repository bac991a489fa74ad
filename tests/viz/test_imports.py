"""The numpy-only modules of sandbox.viz load neither meshcat nor PyBullet."""

from __future__ import annotations

import subprocess
import sys


def test_numpy_modules_import_alone():
    code = (
        "import sys, sandbox.viz.collada, sandbox.viz.meshes, sandbox.viz.geometry\n"
        "print(sorted(m for m in ('meshcat', 'pybullet', 'zmq', 'gymnasium') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_lazy_names_resolve():
    import sandbox.viz

    assert sandbox.viz.Viewer.__name__ == "Viewer"
    assert callable(sandbox.viz.load_mesh)
    try:
        sandbox.viz.Nothing  # noqa: B018
    except AttributeError as error:
        assert "Nothing" in str(error)
    else:
        raise AssertionError("unknown names must raise AttributeError")
