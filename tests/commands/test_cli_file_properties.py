"""Property tests of the command line against bad files and numbers (issue 26, item 1).

Whatever is done to a set's CSV files, or given to a numeric option, a command
either succeeds or fails with status 2 and one ``error:`` line, never a
traceback; and nothing on disk is lost or half-written: the input files are
as they were, an output is whole (it parses) or absent, an existing output
refused without ``--force`` keeps its content, and no temporary file is left.
(Model files: ``tests/core/test_model_files.py``.)
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from hypothesis import given
from hypothesis import strategies as st

from sandbox.cli import main
from tests._hypothesis import property_settings
from tests.commands.test_cli_properties import NUMERIC, TEXT
from tests.data.folders import write_synthetic_set

QUICK = ["--windows", "0.2", "--ratios", "0.5", "--workers", "1", "--no-progress"]
_BASE: dict[str, Path] = {}


def _base_set(tmp_path_factory) -> Path:
    """A valid set: two tasks, three trials each (written once)."""
    if "set" not in _BASE:
        _BASE["set"] = write_synthetic_set(tmp_path_factory.mktemp("base") / "set",
                                           n_per_task=3)
    return _BASE["set"]


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file()}


CELL = st.sampled_from(["", "nan", "inf", "-inf", "1e308", "abc", "1,5", "0x10", "\u00e9",
                        "9" * 40, "-0", " 1 "])
EDIT = st.one_of(
    st.tuples(st.just("cell"), st.integers(0, 10**6), st.integers(0, 40), CELL),
    st.tuples(st.just("header"), st.integers(0, 40), st.sampled_from(["", "t", "x", "T ",
                                                                      "left_s0", "\ufeff t"])),
    st.tuples(st.just("drop_column"), st.integers(0, 40), st.just(None)),
    st.tuples(st.just("time_scale"), st.sampled_from([1e3, 1e6, 1e9, -1.0, 0.0, 1e-6]),
              st.just(None)),
    st.tuples(st.just("truncate"), st.floats(0.0, 1.0), st.just(None)),
    st.tuples(st.just("duplicate_rows"), st.integers(0, 10**6), st.just(None)),
    st.tuples(st.just("bytes"), st.integers(0, 10**6), st.sampled_from([b"\xff", b"\x00",
                                                                         b"\n\n", b'"'])),
)


def _edit(text: bytes, edit) -> bytes:
    kind, a, b = edit[:3]
    if kind in ("truncate", "bytes"):
        if kind == "truncate":
            return text[: int(a * len(text))]
        i = a % max(len(text), 1)
        return text[:i] + b + text[i:]
    lines = text.decode("utf-8", "surrogateescape").split("\n")
    header, rows = lines[0].split(","), [r.split(",") for r in lines[1:] if r]
    if kind == "cell" and rows:
        row = rows[a % len(rows)]
        row[b % len(row)] = edit[3]
    elif kind == "header":
        header[a % len(header)] = b
    elif kind == "drop_column":
        j = a % len(header)
        header.pop(j)
        for r in rows:
            r.pop(j)
    elif kind == "time_scale":
        j = header.index("t") if "t" in header else 0
        for r in rows:
            r[j] = repr(float(r[j]) * a) if _number(r[j]) else r[j]
    elif kind == "duplicate_rows" and rows:
        rows.insert(a % len(rows), list(rows[a % len(rows)]))
    out = "\n".join(",".join(r) for r in [header, *rows]) + "\n"
    return out.encode("utf-8", "surrogateescape")


def _number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _one_line_failure(status: int, err: str) -> None:
    assert "Traceback" not in err, err[-2000:]
    assert status == 2, (status, err[-500:])
    lines = [line for line in err.splitlines() if line.strip()]
    assert lines and "error:" in lines[-1], err[-500:]


@property_settings(10)
@given(edits=st.lists(st.tuples(st.integers(0, 5), EDIT), min_size=1, max_size=3))
def test_a_mutated_set_is_evaluated_or_refused_in_one_line(tmp_path_factory, capsys, edits):
    folder = tmp_path_factory.mktemp("mutated")
    data = folder / "set"
    shutil.copytree(_base_set(tmp_path_factory), data)
    files = sorted(data.rglob("*.csv"))
    for which, edit in edits:
        path = files[which % len(files)]
        path.write_bytes(_edit(path.read_bytes(), edit))
    before = _snapshot(data)
    out = folder / "report.json"
    capsys.readouterr()
    status = main(["evaluate", "--data", str(data), *QUICK, "--no-cache", "--out", str(out)])
    err = capsys.readouterr().err
    assert _snapshot(data) == before                       # the inputs are untouched
    assert sorted(p.name for p in folder.iterdir()) == (["report.json", "set"] if status == 0
                                                        else ["set"])
    if status == 0:
        assert "Traceback" not in err and json.loads(out.read_text())   # whole
    else:
        _one_line_failure(status, err)


#: The numeric options of the commands whose output is checked before any work, with
#: arguments that make them refuse an existing output (so a valid number costs nothing).
REFUSING = {
    ("evaluate",): lambda out: ["evaluate", "--data", "synthetic:two_task", "--out", out],
    ("fit",): lambda out: ["fit", "--data", "synthetic:two_task", "--out", out],
    ("demo",): lambda out: ["demo", "--out", out],
    ("episodes",): lambda out: ["episodes", "--json", out],
}
OPTIONS = [o for o in NUMERIC if tuple(o[0]) in REFUSING]


def test_the_options_cover_the_commands():
    assert {tuple(w) for w, _, _ in OPTIONS} == set(REFUSING) and len(OPTIONS) >= 10


@property_settings(40)
@given(pick=st.sampled_from(OPTIONS), text=TEXT)
def test_a_numeric_option_fails_in_one_line_and_keeps_the_old_output(tmp_path_factory, capsys,
                                                                     pick, text):
    words, option, _ = pick
    folder = tmp_path_factory.mktemp("options")
    old = folder / "old"
    old.write_text("keep")
    capsys.readouterr()
    status = main([*REFUSING[tuple(words)](str(old)), f"{option}={text}"])
    err = capsys.readouterr().err
    _one_line_failure(status, err)
    # a valid number: refused before any work by a check that names its option (the existing
    # output and --force; demo's output name, not .html; evaluate's --test-seed without --test)
    assert f"argument {option}" in err or err.startswith("error: --"), err
    assert old.read_text() == "keep" and [p.name for p in folder.iterdir()] == ["old"]
