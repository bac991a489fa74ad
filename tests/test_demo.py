"""``python -m sandbox demo``: the real demo once (output, outcome, replay in a browser)."""

from __future__ import annotations

import re
import subprocess
import sys

import pytest

from sandbox.cli import main
from tests.viz.test_browser import SIZE, _changed, _project, _screenshot, _window


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    """The demo run in a fresh process, in an empty folder, with its defaults."""
    folder = tmp_path_factory.mktemp("demo")
    out = subprocess.run([sys.executable, "-m", "sandbox", "demo"], capture_output=True,
                         text=True, cwd=folder, timeout=300)
    assert out.returncode == 0, out.stderr[-3000:]
    return out.stdout, folder / "demo.html"


def test_prints_beliefs_over_time_for_both_policies(demo):
    stdout, _ = demo
    assert "switches to 'right'" in stdout
    rows = [line for line in stdout.splitlines() if re.match(r"\s+\d+\.\d\d\s+(up|right)\s", line)]
    assert len(rows) >= 5  # one per dynamic update
    assert any(" right (p=" in row.split("  ")[-1] or "<- the human switched" in row
               for row in rows)
    assert "prior mixture" in rows[0]  # the static baseline has not predicted yet


def test_the_shared_first_half_leaves_the_belief_near_the_prior(demo):
    """Issue 27: the diverging tasks' common first half says nothing about the task (five
    tasks: prior 0.2), so before the switch no task is believed above 0.2 + 0.2."""
    stdout, _ = demo
    before = [line for line in stdout.splitlines()
              if re.match(r"\s+\d+\.\d\d\s+up\s", line)]
    assert len(before) >= 3
    beliefs = [float(re.search(r"\(p=(\d\.\d\d)\)", line).group(1)) for line in before]
    assert max(beliefs) <= 0.4, before


def test_dynamic_hands_over_and_static_does_not(demo):
    stdout, _ = demo
    dynamic = next(line for line in stdout.splitlines() if line.strip().startswith("dynamic:")
                   and "handover" in line)
    static = next(line for line in stdout.splitlines() if line.strip().startswith("static:")
                  and "handover" in line)
    assert "handover at" in dynamic and "final task 'right'" in dynamic
    assert "no handover" in static
    assert re.search(r"wall time \d+\.\d s", stdout)


def test_replay_is_written_and_shows_the_robot(demo, chromium, tmp_path):
    from sandbox.viz import Viewer

    _, html = demo
    assert html.is_file() and html.stat().st_size > 1e6
    empty = Viewer().save_html(tmp_path / "empty.html")
    background = _screenshot(chromium, empty, tmp_path)
    shot = _screenshot(chromium, html, tmp_path, "#t=1.5")
    changed = _changed(background, shot)
    assert changed.mean() > 0.05, "the scene barely shows"
    viewer = Viewer()  # the demo's camera is the default one
    torso = _project(viewer, [0.0, 0.0, 0.3])
    assert _window(changed, torso).mean() > 0.5, "nothing drawn where Baxter's torso stands"
    assert shot.shape == (SIZE[1], SIZE[0], 3)
    h, w = SIZE[1], SIZE[0]
    panel = changed[int(0.04 * h):int(0.16 * h), int(0.16 * w):int(0.32 * w)]
    assert panel.mean() > 0.2, "no task-probability panel in the upper left"


@pytest.mark.parametrize("argv, match", [
    (["--out", "demo.png"], "--out"),
    (["--to-task", "up"], "--to-task"),
    (["--switch", "1.5"], "--switch"),
    (["--dow", "0"], "--dow"),
    (["--from-task", "sideways"], "sideways"),
])
def test_bad_arguments_are_clear_errors(argv, match, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["demo", *argv]) == 2
    assert match in capsys.readouterr().err
    assert not (tmp_path / "demo.html").exists()


def test_the_default_replay_is_replaced_but_no_other_file(tmp_path, monkeypatch):
    """issue 27 item 2: the quickstart could not be run twice ("demo.html exists"). Without
    --out the demo replaces its own previous replay; a foreign demo.html, or an explicit
    --out, still needs --force."""
    from sandbox.cli import build_parser
    from sandbox.commands import demo as command

    monkeypatch.chdir(tmp_path)
    parse = build_parser().parse_args
    (tmp_path / "demo.html").write_text(
        "<!DOCTYPE html>\n<html>\n<head><meta charset=\"utf-8\"><title>handover-sandbox replay"
        "</title>\n")
    args = parse(["demo"])
    command._check(args)
    assert args.out == "demo.html" and args.force
    (tmp_path / "demo.html").write_text("<html><title>my notes</title></html>")
    with pytest.raises(ValueError, match="--force"):
        command._check(parse(["demo"]))
    (tmp_path / "old.html").write_text((tmp_path / "demo.html").read_text())
    with pytest.raises(ValueError, match="--force"):
        command._check(parse(["demo", "--out", "old.html"]))
