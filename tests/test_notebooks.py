"""The tutorial notebooks: committed without outputs, and each runs top to bottom.

Every notebook in ``notebooks/`` is executed with nbclient (kernel ``python3``,
working directory ``notebooks/``), so the tutorials cannot rot. The kernel inherits
this process's environment: with ``SANDBOX_REQUIRE_DATA=1`` (CI)
``02_paper_experiments`` asserts that it ran on the recorded handovers, and the
test passes ``SANDBOX_DATA`` on when it is set (see ``tests/conftest.py``).
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from tests.conftest import RECORDED_SET, recorded_root

NOTEBOOKS_DIR = Path(__file__).resolve().parents[1] / "notebooks"
NOTEBOOKS = sorted(NOTEBOOKS_DIR.glob("*.ipynb"))
EXPECTED = ("01_quickstart", "02_paper_experiments", "03_environment",
            "04_your_own_demonstrations")
#: Per-cell limit (s): generous; each notebook takes under a minute as a whole.
CELL_TIMEOUT = 300


def _read(path: Path):
    nbformat = pytest.importorskip("nbformat")
    return nbformat.read(path, as_version=4)


def test_the_four_tutorials_are_there():
    assert [p.stem for p in NOTEBOOKS] == list(EXPECTED)


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_committed_without_outputs(path):
    import nbformat

    nb = _read(path)
    nbformat.validate(nb)
    dirty = [i for i, cell in enumerate(nb.cells) if cell.cell_type == "code"
             and (cell.get("outputs") or cell.get("execution_count") is not None)]
    assert not dirty, f"{path.name}: code cells {dirty} have outputs; clear them before committing"
    assert nb.metadata.get("kernelspec", {}).get("name") == "python3"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_starts_with_an_introduction(path):
    first = _read(path).cells[0]
    assert first.cell_type == "markdown" and first.source.startswith("# ")


def _require_data() -> bool:
    return os.environ.get("SANDBOX_REQUIRE_DATA", "") not in ("", "0", "false", "no")


def _kernel_env() -> dict[str, str]:
    """Variables to set for the kernel: the recorded data's folder when it is found."""
    env = {"OPENBLAS_NUM_THREADS": os.environ.get("OPENBLAS_NUM_THREADS", "1")}
    root = recorded_root()
    if (root / RECORDED_SET).is_dir():
        env["SANDBOX_DATA"] = str(root.resolve())
    return env


def _printed(nb) -> str:
    return "".join(out.get("text", "") for cell in nb.cells if cell.cell_type == "code"
                   for out in cell.outputs if out.output_type == "stream")


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_runs_without_error(path, monkeypatch):
    nb = _read(path)
    pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel")
    from nbclient import NotebookClient

    for key, value in _kernel_env().items():
        monkeypatch.setenv(key, value)
    client = NotebookClient(nb, timeout=CELL_TIMEOUT, kernel_name="python3",
                            resources={"metadata": {"path": str(NOTEBOOKS_DIR)}})
    client.execute()  # raises CellExecutionError (with the traceback) on any error
    errors = [out for cell in nb.cells if cell.cell_type == "code"
              for out in cell.outputs if out.output_type == "error"]
    assert not errors
    assert all(cell.execution_count for cell in nb.cells if cell.cell_type == "code")
    if path.stem == "02_paper_experiments" and _require_data():
        assert "exp1_recorded:" in _printed(nb), "notebook 02 did not use the recorded handovers"
