"""A fitted model and tuned settings reused by the commands (issue 14, part 1: Reuse).

``evaluate --model`` predicts every trial with a saved model (test-only),
``tune --out`` writes settings that ``--config`` applies to ``fit``,
``evaluate``, ``play`` and ``sweep``, command-line flags winning.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from sandbox.cli import main

SMALL = ["--data", "synthetic:two_task", "--n-per-task", "3"]
#: A quick evaluation: one window, one ratio, in this process.
QUICK = ["--windows", "0.2", "--ratios", "0.5", "--workers", "1", "--no-progress"]


@pytest.fixture(scope="module")
def model_file(tmp_path_factory) -> Path:
    """A model fitted by ``fit`` on synthetic:two_task (seed 0), with 9 basis functions."""
    path = tmp_path_factory.mktemp("model") / "model.npz"
    assert main(["fit", *SMALL, "--n-basis", "9", "--out", str(path)]) == 0
    return path


@pytest.fixture(scope="module")
def heldout_report(model_file, tmp_path_factory) -> dict:
    """``evaluate --model`` on other trials (seed 1) of the same tasks."""
    out = tmp_path_factory.mktemp("report") / "report.json"
    assert main(["evaluate", *SMALL, "--seed", "1", *QUICK, "--model", str(model_file),
                 "--out", str(out)]) == 0
    return json.loads(out.read_text())


def test_model_evaluation_says_it_is_test_only(heldout_report, model_file, capsys):
    config = heldout_report["config"]
    assert config["mode"] == "test-only" and config["model"] == str(model_file)
    assert config["n_basis"] == 9            # the model's own, not EvalConfig's default 21
    assert len(heldout_report["per_trial"]) == sum(heldout_report["n_trials"].values()) == 6
    from sandbox.eval.report import to_markdown

    assert "test-only" in to_markdown(heldout_report)
    assert "leave-one-out, " not in to_markdown(heldout_report)


def test_model_evaluation_predicts_as_the_model_does_directly(heldout_report, model_file):
    """Every trial's dynamic result is that of a DynamicPredictor streamed the trial with
    the saved model: same final task, same goal error (no refit anywhere)."""
    from sandbox.core import DynamicPredictor, IProMP
    from sandbox.eval.datasets import load_pair
    from sandbox.eval.loocv import EvalConfig
    from sandbox.robot import BaxterKinematics

    model = IProMP.load(model_file)
    _, test, _ = load_pair("synthetic:two_task", seed=1, n_per_task=3, observe=("hand",))
    fk = BaxterKinematics().fk
    rows = {r["source"]: r for r in heldout_report["per_trial"]}
    assert set(rows) == {d.source for d in test}
    for demo in test:
        predictor = DynamicPredictor(model, dow_t=0.2, window="all",
                                     **EvalConfig().predictor_options())
        t = demo.times - demo.times[0]
        for ti, yi in zip(t, demo.human):
            predictor.observe(ti, yi)
        mean, _ = predictor.commands(t)
        e_p = float(np.linalg.norm(fk(mean[-1]) - fk(demo.robot[-1])))
        row = rows[demo.source]["dynamic"]["0.2"]
        assert row["recognition"] == float(predictor.task == demo.task)
        assert row["e_p"] == pytest.approx(e_p, abs=1e-6)


@pytest.mark.parametrize(("extra", "words"), [
    (["--observe", "hand,arm"], "--observe: the model given by --model observes hand"),
    (["--data", "synthetic:diverging"], "tasks ['down', 'straight', 'up'] the model does not"),
    (["--tasks", "up"], "--model: --tasks has tasks ['up'] the model does not know"),
])
def test_a_model_that_does_not_fit_the_data_is_one_line(model_file, tmp_path, capsys, extra,
                                                        words):
    out = tmp_path / "r.json"
    argv = ["evaluate", *SMALL, *QUICK, "--model", str(model_file), "--out", str(out), *extra]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1 and "Traceback" not in err
    assert not out.exists()


def test_a_model_folder_with_unknown_tasks_is_refused_before_loading(model_file, tmp_path,
                                                                     capsys):
    for task in ("left", "lift"):
        (tmp_path / "set" / task).mkdir(parents=True)
        (tmp_path / "set" / task / "a.csv").write_text("time,x\n0,1\n")
    assert main(["evaluate", "--data", str(tmp_path / "set"), "--model", str(model_file),
                 "--out", str(tmp_path / "r.json")]) == 2
    assert "has tasks ['lift'] the model does not know" in capsys.readouterr().err


def test_a_file_that_is_no_model_names_the_option(tmp_path, capsys):
    bad = tmp_path / "model.npz"
    bad.write_text("not a model")
    assert main(["evaluate", *SMALL, "--model", str(bad), "--out", str(tmp_path / "r.json")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: --model: model file") and "pickle" not in err


def test_demo_and_play_check_the_model_before_any_work(model_file, tmp_path, capsys):
    """two_task's model knows left and right: the demo's default tasks (up -> right) and a
    hand,arm observation are refused at once, nothing is written."""
    assert main(["demo", "--model", str(model_file), "--out", str(tmp_path / "d.html")]) == 2
    assert "--from-task/--to-task has tasks ['up']" in capsys.readouterr().err
    assert main(["play", "--scenario", "intent_switch", "--model", str(model_file),
                 "--observe", "hand,arm", "--out", str(tmp_path / "s.html")]) == 2
    assert "observe: expected modalities of the model file" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("scenario", "tasks"), [
    ("intent_switch", "['up', 'right'] (human.task/switch_to)"),
    ("human: {}\npolicy: {type: dynamic}\n", "['left', 'right', 'up', 'down', 'straight'] "
                                              "(family 'diverging')"),
    ("human: {task: box}\npolicy: {type: dynamic}\nfamily: objects\n", "['box']"),
])
def test_a_scenario_refuses_a_model_of_other_tasks(model_file, tmp_path, capsys, scenario,
                                                   tasks):
    """issue 26 item 4: `play --scenario intent_switch --model birl.npz` ran to the end
    (exit 0, "no handover") with a model of other tasks; `demo --model` and `evaluate
    --model` refused. two_task's model knows left and right only."""
    if "\n" in scenario:
        (tmp_path / "mine.yaml").write_text(scenario)
        scenario = str(tmp_path / "mine.yaml")
    before = sorted(tmp_path.iterdir())
    assert main(["play", "--scenario", scenario, "--model", str(model_file),
                 "--out", str(tmp_path / "s.html")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"expected a model that knows the human's tasks {tasks}" \
        in err and "got one of ['left', 'right']" in err
    assert sorted(tmp_path.iterdir()) == before


def test_a_recorded_scenario_refuses_a_model_of_other_tasks(model_file, recorded_dir, tmp_path,
                                                            capsys):
    (tmp_path / "rec.yaml").write_text(f"human: {{recorded: {recorded_dir}, task: pencil_box}}\n"
                                       "policy: {type: dynamic}\n")
    assert main(["play", "--scenario", str(tmp_path / "rec.yaml"), "--model", str(model_file),
                 "--out", str(tmp_path / "s.html")]) == 2
    assert "knows the human's tasks ['pencil_box'] (human.task)" in capsys.readouterr().err


def test_a_scenario_runs_with_the_saved_model(model_file, tmp_path, capsys):
    """play --scenario --model: the robot uses the saved model's tasks (left, right)."""
    summary = tmp_path / "s.json"
    assert main(["play", "--scenario", "waypoints", "--model", str(model_file),
                 "--out", str(tmp_path / "s.html"), "--summary", str(summary)]) == 0
    done = json.loads(summary.read_text())
    assert done["model_tasks"] == ["left", "right"] and done["observe"] == ["hand"]


# ------------------------------------------------------------------ settings
def _settings(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "settings.yaml"
    path.write_text(text)
    return path


def test_tune_out_then_config_round_trip(tmp_path, monkeypatch, capsys):
    """tune --out writes the chosen settings; fit and evaluate --config use them."""
    import sandbox.eval.tune as tune

    monkeypatch.setattr(tune, "grid_for", lambda modalities: {"n_basis": (7, 11),
                                                              "likelihood": ("joint",
                                                                             "marginal")})
    settings = tmp_path / "settings.yaml"
    assert main(["tune", *SMALL, "--workers", "1", "--out", str(settings)]) == 0
    chosen = yaml.safe_load(settings.read_text())
    assert set(chosen) == {"observe", "n_basis", "likelihood"} and chosen["observe"] == ["hand"]
    model = tmp_path / "m.npz"
    assert main(["fit", *SMALL, "--config", str(settings), "--out", str(model)]) == 0
    from sandbox.core import IProMP

    assert IProMP.load(model).basis.n_basis == chosen["n_basis"]
    report = tmp_path / "r.json"
    assert main(["evaluate", *SMALL, *QUICK, "--config", str(settings), "--out",
                 str(report)]) == 0
    config = json.loads(report.read_text())["config"]
    assert (config["n_basis"], config["likelihood"]) == (chosen["n_basis"], chosen["likelihood"])


def test_command_line_flags_override_the_settings_file(tmp_path, capsys):
    settings = _settings(tmp_path, "n_basis: 7\nregularizer: 0.01\nobserve: [hand]\n")
    from sandbox.core import IProMP

    for extra, n_basis, regularizer in (([], 7, 0.01), (["--n-basis", "12"], 12, 0.01),
                                        (["--regularizer", "0.1"], 7, 0.1)):
        model = tmp_path / f"m{len(extra)}{n_basis}.npz"
        assert main(["fit", *SMALL, "--config", str(settings), *extra, "--out",
                     str(model)]) == 0
        loaded = IProMP.load(model)
        assert (loaded.basis.n_basis, loaded.regularizer) == (n_basis, regularizer)
    assert main(["fit", *SMALL, "--config", str(settings), "--observe", "hand,arm",
                 "--out", str(tmp_path / "arm.npz")]) == 0
    assert IProMP.load(tmp_path / "arm.npz").modality_names == ("hand", "arm")


def test_sweep_and_play_take_the_settings(tmp_path, monkeypatch):
    """sweep --config: the grid's points start from the file's options; play --config: the
    policy's predictor gets the file's predictor options, the model its model options."""
    import sandbox.eval.sweep as sweep

    settings = _settings(tmp_path, "n_basis: 7\nblend_rate: 20\nwindow_mode: latest\n")
    seen = {}
    monkeypatch.setattr(sweep, "sweep", lambda *a, **kw: seen.update(kw) or
                        {"ranked": [], "failed": []})
    assert main(["sweep", "--data", "synthetic:two_task", "--grid", "g.yaml", "--out",
                 str(tmp_path / "s"), "--config", str(settings)]) == 0
    base = seen["base"]
    assert (base.n_basis, base.blend_rate, base.window_mode) == (7, 20.0, "latest")

    from sandbox.cli import build_parser
    from sandbox.commands.play import _teleop_policy

    args = build_parser().parse_args(["play", "--config", str(settings), "--demos", "3"])
    model, policy, _ = _teleop_policy(args)
    assert model.basis.n_basis == 7
    assert (policy.predictor.blend_rate, policy.predictor.window) == (20.0, "latest")


@pytest.mark.parametrize(("text", "words"), [
    ("n_basis: 9\nblend: 3\n", "unknown key 'blend'; valid keys: observe, n_basis,"),
    ("likelihood: best\n", "likelihood: expected one of ['joint', 'marginal'], got 'best'"),
    ("n_basis: 1\n", "n_basis: expected an integer in [2, 100], got 1"),
    ("settle_tol: -1\n", "settle_tol: expected a finite number in (0, 10] rad or null"),
    ("- 1\n- 2\n", "expected a mapping of options"),
    ("n_basis: [\n", "invalid YAML"),
])
def test_bad_settings_files_are_one_line_naming_the_key(tmp_path, capsys, text, words):
    settings = _settings(tmp_path, text)
    for argv in (["fit", *SMALL, "--out", str(tmp_path / "m.npz")],
                 ["evaluate", *SMALL, "--out", str(tmp_path / "r.json")]):
        assert main([*argv, "--config", str(settings)]) == 2
        err = capsys.readouterr().err
        assert words in err and str(settings) in err and err.count("\n") == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["settings.yaml"]


def test_tune_out_must_be_a_settings_file(tmp_path, capsys):
    assert main(["tune", *SMALL, "--out", str(tmp_path / "tune.md")]) == 2
    assert "the Markdown table is --markdown" in capsys.readouterr().err


def test_model_evaluation_on_workers_gives_the_same_trials(heldout_report, model_file,
                                                           tmp_path):
    out = tmp_path / "r.json"
    quick = [a if a != "1" else "2" for a in QUICK]       # --workers 2
    assert main(["evaluate", *SMALL, "--seed", "1", *quick, "--model", str(model_file),
                 "--out", str(out)]) == 0
    assert json.loads(out.read_text())["per_trial"] == heldout_report["per_trial"]


def test_fit_calibrate_saves_a_familiarity_the_predictor_uses(tmp_path, capsys):
    from sandbox.core import DynamicPredictor, IProMP
    from sandbox.data.datasets import load_dataset

    out = tmp_path / "model.npz"
    assert main(["fit", "--data", "synthetic:two_task", "--n-per-task", "4", "--n-basis", "9",
                 "--calibrate", "--out", str(out)]) == 0
    assert "familiarity calibrated on 8 held-out streams" in capsys.readouterr().out
    model = IProMP.load(out)
    assert model.calibration is not None
    stream = load_dataset("synthetic:two_task", seed=5, n_per_task=2, preprocess="causal")[0]
    predictor = DynamicPredictor(model, 0.2)
    for t, y in zip(stream.times - stream.times[0], stream.human):
        predictor.observe(t, y)
    assert predictor.familiarity is not None and 0 < predictor.familiarity <= 1
    assert predictor.familiar in (True, False)
    assert main(["fit", "--data", "synthetic:two_task", "--n-per-task", "4", "--calibrate",
                 "--preprocess", "causal", "--out", str(tmp_path / "m2.npz")]) == 2


def test_fit_calibrate_takes_the_score_and_the_gate_and_refuses_them_alone(tmp_path, capsys):
    from sandbox.core import IProMP

    out = tmp_path / "gated.npz"
    assert main(["fit", "--data", "synthetic:two_task", "--n-per-task", "4", "--n-basis", "9",
                 "--calibrate", "--score", "goal", "--end-prob", "0.5", "--out", str(out)]) == 0
    cal = IProMP.load(out).calibration
    assert cal.end_prob == 0.5 and "goal" in cal.components
    capsys.readouterr()
    assert main(["fit", "--data", "synthetic:two_task", "--n-per-task", "4", "--end-prob", "0.5",
                 "--out", str(tmp_path / "no.npz")]) == 2
    assert "--score/--end-prob: expected --calibrate" in capsys.readouterr().err
    assert not (tmp_path / "no.npz").exists()
