"""``python -m sandbox ood``: bad input is one line and status 2 before any work; a small run
writes its JSON, Markdown and ROC; ``--records`` re-reports; the old module is an alias."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from sandbox.cli import main


@pytest.mark.parametrize("argv, match", [
    ([], "expected the normal motions"),
    (["--data", "synthetic:objects", "--records", "r.json"], "got both"),
    (["--data", "synthetic:objects", "--model", "m.npz"], "--ood-data too"),
    (["--records", "r.json", "--ood-data", "synthetic-ood:pause"], "no --ood-data"),
    (["--data", "synthetic:objects", "--ood-data", "synthetic-ood:nap"], "FAMILY one of"),
    (["--data", "synthetic:two_task", "--n-per-task", "3"], "at least three tasks"),
    (["--data", "synthetic:objects", "--observe", "emg"], "emg"),
])
def test_bad_input_is_one_line_and_status_2(argv, match, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["ood", "--no-progress", *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("error:") and match in err


def test_existing_outputs_need_force(tmp_path, capsys):
    (tmp_path / "r.json").write_text("{}")
    assert main(["ood", "--data", "synthetic:objects", "--out", str(tmp_path / "r.json")]) == 2
    assert "--force" in capsys.readouterr().err


def test_records_must_be_a_report(tmp_path, capsys):
    (tmp_path / "r.json").write_text("not json")
    assert main(["ood", "--records", str(tmp_path / "r.json")]) == 2
    assert "not JSON" in capsys.readouterr().err
    (tmp_path / "r.json").write_text("[1, 2]")
    assert main(["ood", "--records", str(tmp_path / "r.json")]) == 2


def test_a_small_run_writes_the_report_and_rereports_it(tmp_path, capsys):
    out, md, png = tmp_path / "r.json", tmp_path / "r.md", tmp_path / "roc.png"
    argv = ["ood", "--data", "synthetic:objects", "--ood-data", "synthetic-ood:still@objects",
            "--n-per-task", "3", "--dow-t", "0.5", "--no-progress", "--out", str(out),
            "--markdown", str(md), "--plot", str(png), "--end-prob", "0.5"]
    assert main(argv) == 0
    result = json.loads(out.read_text())
    assert result["mode"] == "ood-sets" and result["n_streams"] == 18
    assert result["end_prob"] == 0.5 and all(len(r["ended"]) == len(r["times"])
                                             for r in result["records"])
    group = result["groups"]["synthetic-ood:still@objects"]
    assert group["n_normal"] == 9 and group["n_ood"] == 9
    assert set(group["at_false_alarm"]) == {"0.01", "0.02", "0.05", "0.1"}
    assert png.stat().st_size > 1000 and "| synthetic-ood:still@objects |" in md.read_text()
    assert "until the estimated end, P >= 0.5" in md.read_text()
    capsys.readouterr()
    assert main(["ood", "--records", str(out), "--alpha", "0.1"]) == 0
    assert "calibrated alpha 0.1" in capsys.readouterr().out


def test_the_old_module_is_a_deprecated_alias(tmp_path):
    done = subprocess.run([sys.executable, "-m", "sandbox.eval.ood", "--records",
                           str(tmp_path / "missing.json")], capture_output=True, text=True,
                          timeout=120)
    assert "deprecated" in done.stderr and "python -m sandbox ood" in done.stderr
    assert done.returncode == 1 and "missing.json" in done.stderr


def test_a_spec_reads_both_sets(tmp_path, capsys):
    """--spec works as for evaluate: the normal and the OOD folder are read with it."""
    from tests.commands.test_observe_cli import write_set

    spec = tmp_path / "spec.yaml"
    spec.write_text("time: stamp\nrobot: [j0, j1, j2, j3, j4, j5, j6]\nobserve: [wrist]\n"
                    "modalities:\n  wrist: {columns: [wx, wy, wz], kind: position}\n"
                    "  grip: {columns: [g0, g1], kind: signal, units: raw}\n")
    normal, odd = write_set(tmp_path / "normal"), write_set(tmp_path / "odd", n_per_task=1)
    out = tmp_path / "r.json"
    assert main(["ood", "--data", str(normal), "--ood-data", str(odd), "--spec", str(spec),
                 "--observe", "wrist,grip", "--dow-t", "0.5", "--no-progress", "--no-cache",
                 "--out", str(out)]) == 0
    result = json.loads(out.read_text())
    assert result["observe"] == "wrist,grip" and result["n_streams"] == 8 + 2
    assert main(["ood", "--data", str(normal), "--ood-data", str(odd), "--observe", "grip",
                 "--no-progress", "--no-cache"]) == 2
    assert "grip" in capsys.readouterr().err
