"""Demonstrations through Minari: ``data export``, ``fit --data minari:ID``, the episode layout.

Needs the optional extra (``pip install -e ".[minari]"``); without it only the
test of the install hint runs. Datasets go to a temporary ``MINARI_DATASETS_PATH``.
"""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from sandbox.cli import main
from sandbox.data.minari_io import load_demonstrations
from sandbox.envs import ENV_IDS
from sandbox.episodes.minari_export import export_demonstrations


def test_without_minari_the_export_says_what_to_install(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "minari", None)   # import minari -> ImportError
    status = main(["data", "export", "--data", "synthetic:diverging", "--minari-id",
                   "sandbox/x-v0"])
    assert status == 1
    assert 'pip install -e ".[minari]"' in capsys.readouterr().err


@pytest.fixture
def minari(tmp_path, monkeypatch):
    """The minari module (skip without the extra), datasets under a temporary folder."""
    if importlib.util.find_spec("minari") is None:
        pytest.skip('Minari is not installed (pip install -e ".[minari]")')
    import minari

    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / "minari"))
    return minari


def _models_equal(a: Path, b: Path, atol: float = 1e-9) -> None:
    """Two saved models hold the same arrays (to ``atol``) and the same metadata."""
    with np.load(a) as fa, np.load(b) as fb:
        assert sorted(fa.files) == sorted(fb.files)
        for key in fa.files:
            if key == "metadata":
                _close(json.loads(str(fa[key])), json.loads(str(fb[key])), atol)
            else:
                np.testing.assert_allclose(fa[key], fb[key], rtol=0, atol=atol, err_msg=key)


def _close(x, y, atol: float) -> None:
    if isinstance(x, dict):
        assert x.keys() == y.keys()
        for k in x:
            _close(x[k], y[k], atol)
    elif isinstance(x, list):
        assert len(x) == len(y)
        for u, v in zip(x, y):
            _close(u, v, atol)
    elif isinstance(x, float):
        assert abs(x - y) <= atol
    else:
        assert x == y


def _fit(data: str, out: Path, *extra: str) -> None:
    assert main(["fit", "--data", data, "--out", str(out), *extra]) == 0


def _export(data: str, dataset_id: str, *extra: str) -> None:
    assert main(["data", "export", "--data", data, "--minari-id", dataset_id, *extra]) == 0


def test_synthetic_round_trip_fits_the_same_model(minari, tmp_path, capsys):
    common = ["--n-per-task", "3", "--observe", "hand,arm"]
    _export("synthetic:diverging", "sandbox/diverging-v0", *common)
    assert "wrote 15 episodes" in capsys.readouterr().out
    _fit("synthetic:diverging", tmp_path / "direct.npz", *common)
    _fit("minari:sandbox/diverging-v0", tmp_path / "minari.npz", "--observe", "hand,arm")
    _models_equal(tmp_path / "direct.npz", tmp_path / "minari.npz")


@pytest.fixture
def few_trials(recorded_dir, tmp_path) -> Path:
    """Three trials of two recorded tasks, linked into a folder of the same layout."""
    root = tmp_path / "few"
    for task in ("pencil_box", "screw_driver"):
        (root / task).mkdir(parents=True)
        for trial in sorted((recorded_dir / task).glob("*.csv"))[:3]:
            (root / task / trial.name).symlink_to(trial)
    return root


def test_recorded_round_trip_fits_the_same_model(minari, few_trials, tmp_path):
    observe = ["--observe", "hand,arm,emg"]
    _export(str(few_trials), "sandbox/recorded-v0", *observe)
    _fit(str(few_trials), tmp_path / "direct.npz", *observe)
    _fit("minari:sandbox/recorded-v0", tmp_path / "minari.npz", *observe)
    _models_equal(tmp_path / "direct.npz", tmp_path / "minari.npz")
    _fit(str(few_trials), tmp_path / "hand.npz")                 # a subset of the modalities
    _fit("minari:sandbox/recorded-v0", tmp_path / "minari_hand.npz")
    _models_equal(tmp_path / "hand.npz", tmp_path / "minari_hand.npz")


def test_episodes_follow_the_documented_layout(minari):
    _export("synthetic:objects", "sandbox/objects-v0", "--n-per-task", "2")
    dataset = minari.load_dataset("sandbox/objects-v0")
    demos, layout = load_demonstrations("sandbox/objects-v0")
    assert layout["preprocess"] == "smooth" and [m["name"] for m in layout["modalities"]] == [
        "hand"]
    for episode, demo in zip(dataset.iterate_episodes(), demos, strict=True):
        obs = episode.observations
        T = demo.n_steps
        assert set(obs) == {"hand", "hand_valid", "q", "time"}
        assert obs["hand"].shape == (T, 3) and episode.actions.shape == (T - 1, 8)
        np.testing.assert_array_equal(episode.actions[:, :7], obs["q"][1:])
        np.testing.assert_array_equal(episode.actions[:, 7], -1.0)
        np.testing.assert_array_equal(obs["time"][:, 0], demo.times - demo.times[0])
        assert episode.terminations[-1] and not episode.terminations[:-1].any()
        assert not episode.truncations.any() and not episode.rewards.any()
        assert set(episode.infos["task"]) == {demo.task}


def test_the_dataset_recovers_a_working_environment(minari):
    _export("synthetic:diverging", "sandbox/env-v0", "--n-per-task", "2")
    dataset = minari.load_dataset("sandbox/env-v0")
    assert dataset.spec.env_spec.id == ENV_IDS[1]
    env = dataset.recover_environment()
    try:
        obs, _ = env.reset(seed=0)
        for key in ("hand", "q", "time"):
            assert dataset.observation_space[key] == env.observation_space[key]
        episode = next(dataset.iterate_episodes())
        obs, *_ = env.step(episode.actions[0])
        assert env.observation_space.contains(obs)
    finally:
        env.close()


def test_missing_samples_round_trip_as_nan_with_a_zero_flag(minari):
    from sandbox.data.datasets import load_dataset

    demo = load_dataset("synthetic:objects", n_per_task=1, preprocess="none")[0]
    human = np.array(demo.human)
    human[5:9] = np.nan
    gappy = demo.replace(human=human)
    export_demonstrations([gappy], "sandbox/gaps-v0", env_id=ENV_IDS[0], preprocess="none")
    back, _ = load_demonstrations("sandbox/gaps-v0")
    np.testing.assert_array_equal(back[0].human, gappy.human)
    episode = next(minari.load_dataset("sandbox/gaps-v0").iterate_episodes())
    assert episode.observations["hand_valid"][5:9].sum() == 0
    assert not episode.observations["hand"][5:9].any()
    human[12, 0] = np.nan                                    # one dim of three: refused
    with pytest.raises(ValueError, match="only some of its dims at row 12"):
        export_demonstrations([demo.replace(human=human)], "sandbox/partial-v0",
                              env_id=ENV_IDS[0], preprocess="none")


@pytest.mark.parametrize("argv, match", [
    (["fit", "--data", "minari:sandbox/none-v0"], "expected a local Minari dataset"),
    (["fit", "--data", "minari:sandbox/exists-v0", "--preprocess", "causal"],
     "preprocessed 'smooth' at export, got 'causal'"),
    (["fit", "--data", "minari:sandbox/exists-v0", "--tasks", "sideways"], "unknown"),
    (["data", "export", "--data", "synthetic:diverging", "--minari-id", "sandbox/exists-v0"],
     "exists already; pass --force"),
    (["data", "export", "--data", "synthetic:diverging", "--minari-id", "sandbox/y-v0",
      "--env-id", "CartPole-v1"], "--env-id"),
])
def test_bad_input_exits_2_with_a_message(minari, tmp_path, capsys, argv, match):
    _export("synthetic:diverging", "sandbox/exists-v0", "--n-per-task", "2")
    if argv[0] == "fit":
        argv = [*argv, "--out", str(tmp_path / "m.npz")]
    assert main(argv) == 2
    assert match in capsys.readouterr().err


def test_force_replaces_a_dataset(minari):
    _export("synthetic:diverging", "sandbox/again-v0", "--n-per-task", "2")
    _export("synthetic:diverging", "sandbox/again-v0", "--n-per-task", "3", "--force")
    assert minari.load_dataset("sandbox/again-v0").total_episodes == 15


# -- play --record-minari ------------------------------------------------------------------

REACH = {"name": "small reach", "seed": 2, "time_limit": 1.0, "family": "diverging",
         "human": {"waypoints": [{"t": 0.0, "position": [1.10, -0.12, 0.25]},
                                 {"t": 0.8, "position": [0.80, 0.18, 0.22]}]},
         "policy": {"type": "dynamic", "dow_t": 0.25}, "model": {"demos": 3, "seed": 1}}


def test_a_played_scenario_is_recorded_by_the_data_collector(minari, tmp_path, capsys):
    path = tmp_path / "reach.json"
    path.write_text(json.dumps(REACH))
    summary_path = tmp_path / "summary.json"
    assert main(["play", "--scenario", str(path), "--out", str(tmp_path / "r.html"),
                 "--summary", str(summary_path), "--record-minari", "sandbox/played-v0"]) == 0
    assert "as the Minari dataset sandbox/played-v0" in capsys.readouterr().out
    summary = json.loads(summary_path.read_text())
    dataset = minari.load_dataset("sandbox/played-v0")
    assert dataset.total_episodes == 1 and dataset.total_steps == summary["steps"]
    env = dataset.recover_environment()
    try:
        assert dataset.observation_space == env.observation_space
        assert dataset.action_space == env.action_space
    finally:
        env.close()
    episode = next(dataset.iterate_episodes())
    assert episode.actions.shape == (summary["steps"], 8)
    assert all(dataset.action_space.contains(a) for a in episode.actions)
    assert bool(episode.terminations[-1]) == summary["success"]
    options = next(iter(dataset.storage.get_episode_metadata([0])))["options"]
    assert options["motion"] == "HumanMotion(task='scripted', source='waypoints[2]')"


def test_an_existing_id_is_refused_before_playing(minari, tmp_path, capsys):
    _export("synthetic:diverging", "sandbox/taken-v0", "--n-per-task", "2")
    assert main(["play", "--scenario", "waypoints", "--out", str(tmp_path / "r.html"),
                 "--record-minari", "sandbox/taken-v0"]) == 2
    err = capsys.readouterr()
    assert "exists already" in err.err and "scenario" not in err.out


def test_teleop_episodes_are_recorded(minari, tmp_path):
    """Teleop with no keys (stdin closed): the clock runs and the episode plays out."""
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    out = subprocess.run([sys.executable, "-m", "sandbox", "play", "--start", "--demos", "2",
                          "--time-limit", "0.4", "--record-minari", "sandbox/teleop-v0"],
                         stdin=subprocess.DEVNULL, capture_output=True, text=True,
                         cwd=tmp_path, env=env, timeout=600)
    assert out.returncode == 0, out.stderr
    assert "recorded 1 episode(s), 20 steps" in out.stdout
    dataset = minari.load_dataset("sandbox/teleop-v0")
    episode = next(dataset.iterate_episodes())
    assert episode.truncations[-1] and episode.actions.shape == (20, 8)
