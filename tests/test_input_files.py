"""Every input file is read within one bound of size and nesting (issue 29, items 3 and 5).

The four readers of a user's files (scenario, settings, sweep grid, spec) share
:func:`sandbox.validation.read_input_text` and :func:`~sandbox.validation.parse_input`:
a FIFO, a folder, a file over ``MAX_INPUT_BYTES``, text that is not UTF-8,
nesting deeper than ``MAX_INPUT_DEPTH`` or more than ``MAX_INPUT_VALUES``
values (YAML aliases counted at each use) are each one ``ValueError`` naming
the file, raised in well under a second. The command-line reproducers of the
issue end with exit status 2 and one line, no traceback.
"""

from __future__ import annotations

import os
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from sandbox.limits import MAX_GRID_POINTS, MAX_INPUT_BYTES, MAX_INPUT_DEPTH, MAX_INPUT_VALUES
from tests.conftest import REPO

#: Generous for a loaded 2-core machine; the reproducers used to take minutes or forever.
TIMEOUT_S = 120


def _scenario(path):
    from sandbox.episodes.scenario_files import load_scenario

    return load_scenario(path)


def _settings(path):
    from sandbox.commands._settings import load

    return load(path)


def _grid(path):
    from sandbox.eval.grid import read_grid

    return read_grid(path)


def _spec(path):
    from sandbox.data.spec import DataSpec

    return DataSpec.load(path)


READERS = {"scenario": _scenario, "settings": _settings, "grid": _grid, "spec": _spec}


def _refused(reader: str, path: Path, match: str) -> str:
    """The one-line message ``READERS[reader]`` refuses ``path`` with (in a thread, bounded)."""
    outcome: list[BaseException | None] = []

    def run():
        try:
            READERS[reader](path)
            outcome.append(None)
        except BaseException as error:  # noqa: BLE001 - the test inspects it
            outcome.append(error)

    worker = threading.Thread(target=run, daemon=True)
    worker.start()
    worker.join(TIMEOUT_S)
    assert outcome, f"{reader} did not answer within {TIMEOUT_S} s"
    error = outcome[0]
    assert isinstance(error, ValueError), repr(error)
    text = str(error)
    assert str(path) in text and "\n" not in text and len(text) < 600, text
    assert match in text, text
    return text


@pytest.mark.parametrize("reader", READERS)
@pytest.mark.parametrize("suffix", [".yaml", ".json"])
def test_a_file_over_the_size_limit_is_refused_unread(tmp_path, reader, suffix):
    path = tmp_path / f"big{suffix}"
    line = "# padding\n" if suffix == ".yaml" else " "
    path.write_text("{}" + line * (MAX_INPUT_BYTES // len(line) + 1))
    _refused(reader, path, "MAX_INPUT_BYTES")


@pytest.mark.parametrize("reader", READERS)
def test_a_30_mb_file_is_refused_at_once(tmp_path, reader):
    """Issue 29 item 3: a 30 MB YAML file got no answer within 60-120 s."""
    path = tmp_path / "huge.yaml"
    with open(path, "w") as fh:
        fh.write("a: [")
        fh.write("1, " * 10_000_000)
        fh.write("1]\n")
    _refused(reader, path, "MAX_INPUT_BYTES")


def _nested(kind: str, depth: int) -> str:
    if kind == "flow":
        return "a: " + "[" * depth + "]" * depth + "\n"
    if kind == "json":
        return '{"a": ' + "[" * depth + "]" * depth + "}"
    return "".join(f"{' ' * i}k{i}:\n" for i in range(depth)) + " " * depth + "k: 1\n"


@pytest.mark.parametrize("reader", READERS)
@pytest.mark.parametrize("kind, depth", [("flow", 100_000), ("json", 100_000),
                                         ("flow", MAX_INPUT_DEPTH + 1),
                                         ("block", MAX_INPUT_DEPTH + 1), ("block", 600)])
def test_deep_nesting_is_refused(tmp_path, reader, kind, depth):
    """Issue 29 item 3: 100,000 levels gave 'unexpected RecursionError ... please report it'."""
    path = tmp_path / ("deep.json" if kind == "json" else "deep.yaml")
    path.write_text(_nested(kind, depth))
    _refused(reader, path, "MAX_INPUT_DEPTH")


LAUGHS = "\n".join(["a: &a [x, x, x, x, x, x, x, x, x, x]"]
                   + [f"{chr(98 + i)}: &{chr(98 + i)} [{', '.join(['*' + chr(97 + i)] * 10)}]"
                      for i in range(8)]) + "\n"


@pytest.mark.parametrize("reader", READERS)
def test_a_billion_laughs_file_is_refused_before_it_is_walked(tmp_path, reader):
    path = tmp_path / "laughs.yaml"
    path.write_text(LAUGHS)
    _refused(reader, path, "MAX_INPUT_VALUES")


def test_values_are_counted_with_aliases_expanded():
    from sandbox.validation import check_input_size

    shared = list(range(MAX_INPUT_VALUES // 10))
    check_input_size({"a": shared})
    with pytest.raises(ValueError, match="MAX_INPUT_VALUES"):
        check_input_size({"a": [shared] * 11})
    deep: list = []
    inner = deep
    for _ in range(MAX_INPUT_DEPTH - 1):
        inner.append([])
        inner = inner[0]
    check_input_size(deep)
    inner.append([])
    with pytest.raises(ValueError, match="MAX_INPUT_DEPTH"):
        check_input_size(deep)


@pytest.mark.parametrize("reader", READERS)
def test_text_that_is_not_utf8_names_the_file(tmp_path, reader):
    """Issue 29 item 5: "'utf-8' codec can't decode byte 0xff", with no file name."""
    path = tmp_path / "latin.yaml"
    path.write_bytes(b"name: caf\xe9\n\xff\n")
    text = _refused(reader, path, "expected UTF-8 text, got byte 0xe9 at offset 9")
    assert "codec" not in text


@pytest.mark.skipif(os.name != "posix", reason="FIFOs")
@pytest.mark.parametrize("reader", READERS)
def test_a_fifo_or_a_folder_is_refused_without_blocking(tmp_path, reader):
    fifo = tmp_path / "fifo.yaml"
    os.mkfifo(fifo)
    _refused(reader, fifo, "")                       # "regular file" or "an existing file"
    folder = tmp_path / "folder.yaml"
    folder.mkdir()
    _refused(reader, folder, "")


@pytest.mark.parametrize("reader", READERS)
@pytest.mark.parametrize("text", ["a: 2001-02-30\n", "a: !!python/object:os.system ls\n",
                                  "? [a, b]\n: 1\n", "a: 1\na: 2\n", "{", "a: " + "9" * 5000])
def test_odd_yaml_is_one_value_error(tmp_path, reader, text):
    path = tmp_path / "odd.yaml"
    path.write_text(text)
    with pytest.raises(ValueError) as info:
        READERS[reader](path)
    assert str(path) in str(info.value) and "\n" not in str(info.value)


def test_a_file_at_the_limit_is_read(tmp_path):
    path = tmp_path / "settings.yaml"
    body = "n_basis: 9\n"
    path.write_text(body + "#" * (MAX_INPUT_BYTES - len(body) - 1) + "\n")
    assert path.stat().st_size == MAX_INPUT_BYTES
    assert _settings(path) == {"n_basis": 9}


# ------------------------------------------------------------------------------ grids


def test_a_grid_is_counted_before_it_is_expanded(tmp_path):
    """Issue 29 item 3: 3 x 1,000 values built the whole product: MemoryError."""
    path = tmp_path / "grid.yaml"
    values = ", ".join(str(15 + i % 50) for i in range(1000))
    path.write_text(f"n_basis: [{values}]\nn_candidates: [{values}]\nrefine_steps: [{values}]\n")
    text = _refused("grid", path, "MAX_GRID_POINTS")
    assert "1000000000" in text


def test_unknown_names_are_refused_before_counting(tmp_path):
    path = tmp_path / "grid.yaml"
    values = ", ".join(["1"] * 1000)
    path.write_text(f"colour: [{values}]\nsize: [{values}]\nshape: [{values}]\n")
    _refused("grid", path, "colour: unknown option")


def test_a_grid_at_the_limit_is_expanded(tmp_path):
    from sandbox.eval.grid import read_grid

    path = tmp_path / "grid.yaml"
    n = MAX_GRID_POINTS // 2
    path.write_text(f"dow_t: [{', '.join(str(0.01 * (i + 1)) for i in range(n))}]\n"
                    "likelihood: [joint, marginal]\n")
    assert len(read_grid(path)) == MAX_GRID_POINTS
    points = tmp_path / "points.yaml"
    points.write_text("points:\n" + "".join(f"  - {{dow_t: {0.01 * (i + 1):.2f}}}\n"
                                            for i in range(MAX_GRID_POINTS + 1)))
    _refused("grid", points, "MAX_GRID_POINTS")


# ----------------------------------------------------------------- messages (item 5)


def test_unknown_policy_options_name_the_valid_ones(tmp_path):
    """Issue 29 item 5: 'PredictorBase.__init__() got an unexpected keyword argument'."""
    path = tmp_path / "s.yaml"
    path.write_text("human: {task: up}\npolicy: {type: dynamic, options: {colour: 1}}\n")
    text = _refused("scenario", path, "policy.options: expected keys among")
    assert "colour" in text and "blend_rate" in text and "__init__" not in text
    path.write_text("human: {task: up}\npolicy: {type: dynamic}\nmodel: {options: {hue: 1}}\n")
    text = _refused("scenario", path, "model.options: expected keys among")
    assert "hue" in text and "n_basis" in text and "__init__" not in text


@pytest.mark.parametrize("text, match", [
    ("time: left_s0\n", "time: expected a column other than the robot columns"),
    ("robot: [a, b, a]\n", "robot: expected distinct column names, got ['a']"),
])
def test_a_spec_with_clashing_columns_is_refused_up_front(tmp_path, text, match):
    path = tmp_path / "spec.yaml"
    path.write_text(text)
    _refused("spec", path, match)


# ------------------------------------------------------------- the CLI reproducers


def _cli(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(REPO), "SANDBOX_CACHE_DIR": str(cwd / "cache")}
    return subprocess.run([sys.executable, "-m", "sandbox", *args], capture_output=True,
                          text=True, timeout=TIMEOUT_S, env=env, cwd=cwd)


def _one_line_exit_2(done: subprocess.CompletedProcess, *words: str) -> None:
    assert done.returncode == 2, (done.returncode, done.stderr[-2000:])
    lines = [line for line in done.stderr.strip().splitlines()
             if not line.startswith("pybullet build time")]     # printed by pybullet's C code
    assert len(lines) == 1 and lines[0].startswith("error: "), done.stderr[-2000:]
    assert "Traceback" not in done.stderr and "please report" not in done.stderr
    for word in words:
        assert word in lines[0], lines[0]


def test_cli_reproducers_of_oversized_and_nested_files_exit_2(tmp_path):
    deep = tmp_path / "deep.yaml"
    deep.write_text(_nested("flow", 100_000))
    big = tmp_path / "big.yaml"
    big.write_text("{}" + "#\n" * (MAX_INPUT_BYTES // 2 + 1))
    for path, limit in ((deep, "MAX_INPUT_DEPTH"), (big, "MAX_INPUT_BYTES")):
        for args in (["play", "--scenario", str(path)],
                     ["fit", "--data", "synthetic:two_task", "--out", "m.npz", "--config",
                      str(path)],
                     ["fit", "--data", "synthetic:two_task", "--out", "m.npz", "--spec",
                      str(path)],
                     ["sweep", "--data", "synthetic:two_task", "--grid", str(path), "--out",
                      "sweep"]):
            _one_line_exit_2(_cli(args, tmp_path), str(path), limit)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["big.yaml", "deep.yaml"]


def test_cli_reproducers_of_values_past_the_table_exit_2(tmp_path):
    scenario = tmp_path / "s.yaml"
    scenario.write_text("human: {task: up}\npolicy: {type: dynamic}\nmodel: {demos: 10000000}\n")
    _one_line_exit_2(_cli(["play", "--scenario", str(scenario)], tmp_path),
                     "model.demos", "[2, 10000]")
    scenario.write_text("human:\n  waypoints:\n    - {t: 0, position: [1.1, -0.1, 0.25]}\n"
                        "    - {t: 1.5, position: [0.8, 0.0, 0.25]}\n"
                        "  tracker: {noise_m: 1.0e+300}\npolicy: {type: dynamic}\n")
    _one_line_exit_2(_cli(["play", "--scenario", str(scenario)], tmp_path),
                     "noise_m")
    settings = tmp_path / "settings.yaml"
    settings.write_text("noise_floor: 1.0e+6\n")
    _one_line_exit_2(_cli(["fit", "--data", "synthetic:two_task", "--out", "m.npz",
                           "--config", str(settings)], tmp_path), "noise_floor", "[1e-12, 1]")
    settings.write_text("observe: [hand]\nnoise_floors: {colour: 0.02}\n")
    _one_line_exit_2(_cli(["fit", "--data", "synthetic:two_task", "--out", "m.npz",
                           "--config", str(settings)], tmp_path), "noise_floors", "colour")
    grid = tmp_path / "grid.yaml"
    grid.write_text("dow_t: [1.0e+9]\n")
    _one_line_exit_2(_cli(["sweep", "--data", "synthetic:two_task", "--grid", str(grid),
                           "--out", "sweep"], tmp_path), "dow_t", "(0, 60]")
    grid.write_text("n_candidates: [1000000]\n")
    _one_line_exit_2(_cli(["sweep", "--data", "synthetic:two_task", "--grid", str(grid),
                           "--out", "sweep"], tmp_path), "n_candidates", "[3, 1000]")
    _one_line_exit_2(_cli(["fit", "--data", "synthetic:two_task", "--human-columns", "a,b,c",
                           "--out", "m.npz"], tmp_path), "--human-columns")
    _one_line_exit_2(_cli(["fit", "--data", "minari:" + "x" * 5000, "--out", "m.npz"],
                          tmp_path), "MAX_NAME_CHARS")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["grid.yaml", "s.yaml",
                                                         "settings.yaml"]


def test_an_unknown_modality_in_noise_floors_is_refused_by_the_fit():
    import numpy as np

    from sandbox.core import IProMP
    from sandbox.data.synthetic import two_task_demos

    with pytest.raises(ValueError, match=r"noise_floors: expected floors of the demonstrations' "
                                         r"modalities \['hand'\], got \['colour'\]"):
        IProMP(n_basis=7, noise_floors={"colour": 0.02}).fit(
            two_task_demos(3, np.random.default_rng(0)))


def test_fit_makes_a_missing_output_folder_like_play(tmp_path):
    """Issue 29 item 5: one rule for output folders: missing ones are made."""
    done = _cli(["fit", "--data", "synthetic:two_task", "--n-per-task", "3", "--n-basis", "7",
                 "--out", "new/dir/m.npz"], tmp_path)
    assert done.returncode == 0, done.stderr[-2000:]
    assert (tmp_path / "new" / "dir" / "m.npz").is_file()
    (tmp_path / "file").write_text("keep")
    done = _cli(["fit", "--data", "synthetic:two_task", "--out", "file/m.npz"], tmp_path)
    assert done.returncode == 2 and "Traceback" not in done.stderr    # argparse: usage, error
    assert "argument --out: expected a path under folders ('file' is a file)" in done.stderr
    assert (tmp_path / "file").read_text() == "keep"


@pytest.mark.parametrize("reader", READERS)
@pytest.mark.parametrize("name", ["y" * 5000 + ".yaml", "nul\0.yaml"])
def test_a_name_the_system_refuses_is_one_value_error(tmp_path, reader, name):
    """Issue 29 item 5: '[Errno 36] File name too long' (rc 1) for an over-long name."""
    with pytest.raises(ValueError) as info:
        READERS[reader](tmp_path / name)
    assert "\n" not in str(info.value) and "Errno" not in str(info.value)


def test_a_long_real_path_is_named_whole_and_garbage_is_cut(tmp_path):
    """A path in a deep folder (pytest-xdist's temporary folders are 80+ characters) is
    named whole in the one-line refusal; a megabyte name is cut, with its length."""
    from sandbox.data.datasets import load_dataset
    from sandbox.episodes.scenario_files import resolve

    deep = tmp_path.joinpath(*["a_rather_long_folder_name"] * 6) / "missing.yaml"
    for refuse in (resolve, load_dataset):
        with pytest.raises(ValueError) as error:
            refuse(str(deep))
        assert str(deep) in str(error.value) and "\n" not in str(error.value)
    with pytest.raises(ValueError, match=r"\.\.\. \(1000000 characters\)") as error:
        resolve("x" * 1_000_000)
    assert len(str(error.value)) < 600
