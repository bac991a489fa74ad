"""Sweeps: grid files, keys, the output folder, and the same results on every executor."""

import os
from concurrent.futures import Future
from pathlib import Path

import pytest

import sandbox
from sandbox.eval import executors
from sandbox.eval.evaluation import chunk_folds, config_key, data_token
from sandbox.eval.executors import ProcessExecutor, Task, run_task
from sandbox.eval.grid import config_for, parse_grid, read_grid
from sandbox.eval.loocv import EvalConfig
from sandbox.eval.sweep import load_result, run_sweep, stored_results

REPO = Path(__file__).resolve().parents[2]
BASE = EvalConfig(observe=("hand",), n_candidates=10, subsample=4)   # quick folds
POINTS = [{"n_basis": 15, "dow_t": 1.0}, {"n_basis": 21, "likelihood": "marginal", "dow_t": 1.0}]
ALWAYS = {"n_basis": 15, "blend_rate": 20.0, "dow_t": 1.0}    # its worker dies on every try
ONCE = {"n_basis": 15, "blend_rate": 100.0, "dow_t": 1.0}     # its worker dies on the first


@pytest.fixture(scope="module")
def trials():
    from sandbox.eval.datasets import load_pair

    train, test, _ = load_pair("synthetic:two_task", seed=0, n_per_task=3)
    return {("hand",): (train, test)}


@pytest.fixture
def worker_env(monkeypatch):
    """Worker processes import this checkout (spawned processes do not inherit sys.path)."""
    path = os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")]))
    monkeypatch.setenv("PYTHONPATH", path)
    return monkeypatch


class Inline:
    """An executor that runs each task in this process when it is submitted."""

    def __init__(self):
        self.submitted = []

    def load(self, token, train, test):
        executors.install(token, train, test)

    def slots(self):
        return 1

    def capacity(self):
        return 1

    def submit(self, task):
        self.submitted.append(task)
        future = Future()
        try:
            future.set_result(run_task(task))
        except Exception as error:
            future.set_exception(error)
        return future

    def wait(self, futures):
        return set(futures)

    def result(self, future):
        return future.result()


def _key(trials, point):
    return config_key(config_for(point, BASE), data_token(*trials[("hand",)]))


def _sweep(executor, trials, points, out, **kw):
    return run_sweep(executor, trials, points, out, base=BASE, log=lambda _: None, **kw)


# ---------------------------------------------------------------- grid files
def test_lists_give_their_product_and_points_are_listed():
    product = parse_grid({"n_basis": [15, 21], "likelihood": ["joint", "marginal"]})
    assert len(product) == 4 and {"n_basis": 21, "likelihood": "joint"} in product
    points = parse_grid({"points": [{"n_basis": 15}, {"n_basis": 21, "window": "latest"}]})
    assert points == [{"n_basis": 15}, {"n_basis": 21, "window_mode": "latest"}]


def test_values_are_converted_as_their_option_takes_them(tmp_path):
    grid = tmp_path / "grid.yaml"      # YAML 1.1 reads 1e-3 as a string
    grid.write_text("regularizer: [1e-3, 0.01]\nobserve: [hand, 'hand,arm']\n"
                    "noise_floors: [{arm: 0.02}]\nsettle_tol: [null]\nn_basis: [15, 15]\n")
    points = read_grid(grid)
    assert [p["regularizer"] for p in points] == [0.001, 0.001, 0.01, 0.01]
    assert points[1]["observe"] == ("hand", "arm")
    assert points[0]["noise_floors"] == (("arm", 0.02),) and points[0]["settle_tol"] is None
    config = config_for({**points[0], "dow_t": 0.5}, BASE)
    assert config.windows == (0.5,) and config.ratios == (0.3,) and config.regularizer == 0.001


@pytest.mark.parametrize("text, expected", [
    ("n_basis: []", "n_basis: expected a non-empty list"),
    ("n_bases: [15]", "n_bases: unknown option"),
    ("points: []", "points: expected a non-empty list"),
    ("points: [{n_basis: 15, speed: 2}]", "points[0].speed: unknown option"),
    ("likelihood: [joint, best]", "likelihood: expected one of ['joint', 'marginal']"),
    ("n_basis: [15.5]", "n_basis: expected an integer in [2, 100]"),
    ("n_basis: 15", "n_basis: expected a non-empty list of values, got 15"),
    ("window: [all]\nwindow_mode: [all]", "'window_mode' is given twice"),
])
def test_a_bad_grid_is_a_clear_error(tmp_path, text, expected):
    grid = tmp_path / "grid.yaml"
    grid.write_text(text + "\n")
    with pytest.raises(ValueError, match="grid .*grid.yaml") as info:
        read_grid(grid)
    assert expected in str(info.value)


def test_a_missing_grid_file_is_a_clear_error(tmp_path):
    with pytest.raises(ValueError, match="--grid: expected an existing"):
        read_grid(tmp_path / "nothing.yaml")


# ---------------------------------------------------------------- keys and chunks
def test_the_folds_are_split_into_consecutive_chunks():
    for n, configs, slots, size in [(174, 8, 2, None), (5, 1, 4, None), (7, 3, 1, 3),
                                    (1, 9, 2, None)]:
        chunks = chunk_folds(n, configs, slots, size)
        assert [i for c in chunks for i in c] == list(range(n))
    assert len(chunk_folds(174, 8, 2)) == 8          # 64 tasks for 2 workers


def test_the_key_changes_with_any_option_the_trials_or_the_version(trials, monkeypatch):
    token = data_token(*trials[("hand",)])
    key = config_key(BASE, token)
    assert key == config_key(EvalConfig(observe=("hand",), n_candidates=10, subsample=4), token)
    assert key != config_key(EvalConfig(observe=("hand",), n_candidates=10, subsample=5), token)
    assert key != config_key(BASE, data_token(*[t[:-1] for t in trials[("hand",)]]))
    monkeypatch.setattr(sandbox, "__version__", "0.0.0")
    assert key != config_key(BASE, token)


# ---------------------------------------------------------------- the output folder
def test_a_rerun_skips_what_is_done_and_a_changed_grid_is_refused(trials, tmp_path):
    out = tmp_path / "sweep"
    first = Inline()
    summary = _sweep(first, trials, POINTS, out)
    assert len(summary["ranked"]) == 2 and len(first.submitted) > 0
    assert [e["J"] for e in summary["ranked"]] == sorted(e["J"] for e in summary["ranked"])
    assert {"summary.md", "summary.json", "summary.png", "sweep.json"} <= {
        p.name for p in out.iterdir()}
    again = Inline()
    assert _sweep(again, trials, POINTS, out)["ranked"] == summary["ranked"]
    assert again.submitted == []                          # nothing recomputed
    changed = [{"n_basis": 15, "end_prob": 0.8}]
    with pytest.raises(ValueError, match="another sweep's results; use --force"):
        _sweep(Inline(), trials, changed, out)
    forced = Inline()
    summary = _sweep(forced, trials, changed, out, force=True)
    assert len(forced.submitted) > 0                      # a stale result is not reused
    assert [e["point"] for e in summary["ranked"]] == [{"n_basis": 15, "end_prob": 0.8}]


def test_an_interrupted_sweep_rerun_computes_only_what_is_missing(trials, tmp_path):
    def interrupt(line):
        if line.startswith("[1/2]"):
            raise KeyboardInterrupt

    out = tmp_path / "out"
    with pytest.raises(KeyboardInterrupt):
        run_sweep(Inline(), trials, POINTS, out, base=BASE, log=interrupt)
    assert len(list((out / "results").glob("*.json"))) == 1 and not (out / "summary.md").exists()
    rerun = Inline()
    summary = _sweep(rerun, trials, POINTS, out)
    assert {t.key for t in rerun.submitted} == {_key(trials, POINTS[1])}
    assert len(summary["ranked"]) == 2


def test_a_folder_of_other_files_is_refused(trials, tmp_path):
    (tmp_path / "notes.txt").write_text("mine")
    with pytest.raises(ValueError, match="files that are not a sweep's"):
        _sweep(Inline(), trials, POINTS, tmp_path)


def test_results_are_written_atomically(trials, tmp_path, monkeypatch):
    """A result file is complete or absent: it appears by os.replace of a finished file."""
    replaced = []
    real = os.replace
    monkeypatch.setattr(os, "replace", lambda a, b: (replaced.append((a, b)), real(a, b)))
    _sweep(Inline(), trials, POINTS[:1], tmp_path / "out")
    moved = [(Path(a), Path(b)) for a, b in replaced if Path(b).parent.name == "results"]
    assert len(moved) == 1 and moved[0][0].parent == moved[0][1].parent
    assert load_result(tmp_path / "out", moved[0][1].stem)["point"] == POINTS[0]
    assert not list((tmp_path / "out" / "results").glob(".*"))


# ---------------------------------------------------------------- executors
def test_workers_must_be_a_positive_integer():
    with pytest.raises(ValueError, match="--workers: expected an integer >= 1, got 0"):
        executors.open_executor(0)


def _crash(trials, tmp_path, monkeypatch) -> tuple[Path, Path]:
    """Make the workers of ALWAYS die on every try and those of ONCE on the first only;
    returns the files counting their deaths."""
    always, once = tmp_path / "always-died", tmp_path / "once-died"
    monkeypatch.setenv(executors.CRASH_HOOK, f"{_key(trials, ALWAYS)}*9@{always},"
                                             f"{_key(trials, ONCE)}@{once}")
    return always, once


def _deaths(path: Path) -> int:
    return path.read_text().count("\n") if path.exists() else 0


@pytest.mark.slow
def test_one_worker_and_one_fold_per_task_give_the_samestored_results(trials, tmp_path, worker_env):
    _sweep(Inline(), trials, POINTS, tmp_path / "inline")
    with ProcessExecutor(1) as ex:
        _sweep(ex, trials, POINTS, tmp_path / "one", chunk_size=1)
    assert len(stored_results(tmp_path / "inline")) == 2
    assert stored_results(tmp_path / "one") == stored_results(tmp_path / "inline")


@pytest.mark.slow
def test_two_workers_give_the_same_results_and_a_dying_worker_loses_only_its_task(
        trials, tmp_path, worker_env):
    always, once = _crash(trials, tmp_path, worker_env)
    _sweep(Inline(), trials, POINTS, tmp_path / "inline")
    with ProcessExecutor(2) as ex:       # one task per configuration: its deaths are counted
        summary = _sweep(ex, trials, POINTS + [ALWAYS, ONCE], tmp_path / "two", chunk_size=6)
    assert (_deaths(always), _deaths(once)) == (2, 1)   # tried, retried once; retried, done
    [failed] = summary["failed"]
    assert failed["label"] == "n_basis=15, blend_rate=20, dow_t=1" and "died" in failed["error"]
    assert len(summary["ranked"]) == 3 and "Failed" in (tmp_path / "two" / "summary.md").read_text()
    two, inline = stored_results(tmp_path / "two"), stored_results(tmp_path / "inline")
    assert {k: two[k] for k in inline} == inline


@pytest.mark.slow
def test_dask_gives_the_same_results_and_retries_a_dead_worker_once(trials, tmp_path,
                                                                   worker_env):
    pytest.importorskip("distributed")
    from sandbox.eval.dask_executor import DaskExecutor

    always, _ = _crash(trials, tmp_path, worker_env)
    _sweep(Inline(), trials, POINTS, tmp_path / "inline")
    with DaskExecutor("local", workers=2) as ex:    # one task per configuration, as above
        assert ex.capacity() == ex.slots() == 2     # none waits on a worker that may die
        trim = ex.client.run(os.environ.get, "MALLOC_TRIM_THRESHOLD_")
        assert set(trim.values()) == {os.environ.get("MALLOC_TRIM_THRESHOLD_")}  # not Dask's
        summary = _sweep(ex, trials, POINTS + [ALWAYS], tmp_path / "dask", chunk_size=6)
    assert _deaths(always) == 2 and len(summary["ranked"]) == 2
    assert [f["label"] for f in summary["failed"]] == ["n_basis=15, blend_rate=20, dow_t=1"]
    assert stored_results(tmp_path / "dask") == stored_results(tmp_path / "inline")


def test_without_dask_the_scheduler_option_says_how_to_install_it(monkeypatch):
    pytest.importorskip("distributed")
    from sandbox.eval import dask_executor

    monkeypatch.setattr(dask_executor, "_MISSING", ImportError("No module named 'distributed'"))
    with pytest.raises(ValueError, match=r'pip install -e "\.\[dask\]"'):
        executors.open_executor(2, "local")


def test_an_unreachable_scheduler_is_named_after_a_short_wait():
    pytest.importorskip("distributed")
    with pytest.raises(ValueError, match=r"no Dask scheduler answered at 'tcp://127.0.0.1:9' "
                                         r"within 1 s"):
        executors.open_executor(1, "tcp://127.0.0.1:9", timeout=1)


def test_a_task_runs_in_a_worker_with_its_trials_installed(trials):
    train, test = trials[("hand",)]
    token = data_token(train, test)
    executors.install(token, train, test)
    config = config_for(POINTS[0], BASE)
    results, seconds = run_task(Task("k", config, (0, 1), token))
    assert [r["task"] for r in results] == [train[0].task, train[1].task] and seconds > 0
    with pytest.raises(RuntimeError, match="not installed"):
        run_task(Task("k", config, (0,), "other"))


@pytest.mark.slow
def test_the_sweep_benchmark_reports_wall_times_ratios_and_cores(worker_env):
    from sandbox.bench.sweep import run_sweep_benchmark

    grid = {"n_basis": [15], "likelihood": ["joint", "marginal"], "n_candidates": [10],
            "subsample": [4], "dow_t": [1.0]}
    result = run_sweep_benchmark("synthetic:two_task", n_per_task=3, dask=False, grid=grid)
    assert result["cores"] == os.cpu_count() and result["folds"] == 6
    assert result["configurations"] == 2 and result["identical"]
    assert result["speedup"] == pytest.approx(
        result["sweep_1_worker_s"] / result["sweep_2_workers_s"], rel=0.01)


def test_evaluate_benchmark_reports_cold_warm_and_first_progress():
    from sandbox.bench.evaluate import run

    result = run("synthetic:two_task", repeats=1, workers=1, n_per_task=3)
    assert result["cpu_count"] == os.cpu_count() and result["trials"] > 0
    for case in ("cold", "warm"):
        wall = result[f"evaluate_{case}_wall_s"]
        assert 0 < result[f"evaluate_{case}_first_progress_s"] < wall
        assert 0 < result[f"evaluate_{case}_loocv_runtime_s"] < wall
    assert result["warm_vs_cold_wall_ratio"] > 0
