"""Tests of sandbox.data.cache: loaded trials kept on disk, keyed by content and options."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sandbox.data import cache as cache_module
from sandbox.data.cache import TrialCache, default_folder, resolve_cache
from sandbox.data.filtering import FilterConfig
from sandbox.data.recorded import TrialError, load_recorded, load_trial
from sandbox.data.spec import DataSpec
from tests.data.test_recorded import HEADER, make_bad, trial_rows, write_csv


@pytest.fixture
def trial(tmp_path: Path) -> Path:
    return write_csv(tmp_path / "data" / "reach" / "trial1.csv", HEADER, trial_rows())


def assert_same_demo(a, b) -> None:
    for name in ("times", "human", "robot"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert (a.task, a.source, a.human_names, a.robot_names, a.modalities) == \
        (b.task, b.source, b.human_names, b.robot_names, b.modalities)
    assert a.meta["report"] == b.meta["report"]
    np.testing.assert_array_equal(a.meta["modality_measured"], b.meta["modality_measured"])
    np.testing.assert_array_equal(a.meta["human_measured"], b.meta["human_measured"])


@pytest.mark.parametrize("preprocess", ["none", "causal", "smooth"])
def test_a_cached_trial_is_the_loaded_one(trial, tmp_path, preprocess):
    store = TrialCache(tmp_path / "cache")
    fresh = load_trial(trial, preprocess=preprocess)
    first = load_trial(trial, preprocess=preprocess, cache=store)
    again = load_trial(trial, preprocess=preprocess, cache=store)
    assert (store.misses, store.hits) == (1, 1)
    assert_same_demo(first, fresh)
    assert_same_demo(again, fresh)
    assert not again.human.flags.writeable


@pytest.mark.parametrize("preprocess", ["causal", "smooth"])
def test_a_recorded_trial_with_every_modality_round_trips(recorded_dir, tmp_path, preprocess):
    path = sorted((recorded_dir / "box").glob("*.csv"))[0] if (recorded_dir / "box").is_dir() \
        else sorted(recorded_dir.glob("*/*.csv"))[0]
    store = TrialCache(tmp_path / "cache")
    fresh = load_trial(path, preprocess=preprocess, observe="hand,arm,emg")
    load_trial(path, preprocess=preprocess, observe="hand,arm,emg", cache=store)
    assert_same_demo(load_trial(path, preprocess=preprocess, observe="hand,arm,emg",
                                cache=store), fresh)
    assert store.hits == 1 and [m.kind for m in fresh.modalities] == ["position"] * 2 + ["signal"]


def test_other_options_content_or_code_are_other_entries(trial, tmp_path, monkeypatch):
    store = TrialCache(tmp_path / "cache")
    load_trial(trial, cache=store)
    load_trial(trial, preprocess="causal", cache=store)
    load_trial(trial, config=FilterConfig(accel_std=3.0), cache=store)
    load_trial(trial, max_fill_s=0.5, cache=store)
    load_trial(trial, task="other", cache=store)
    assert (store.misses, store.hits) == (5, 0)
    rows = trial_rows()
    rows[5][1] += 0.01
    write_csv(trial, HEADER, rows)                        # same path, new content
    changed = load_trial(trial, cache=store)
    assert store.misses == 6
    assert_same_demo(changed, load_trial(trial))
    monkeypatch.setattr(cache_module, "_code_digest", lambda: "another version")
    load_trial(trial, cache=store)
    assert (store.misses, store.hits) == (7, 0)
    assert store.size()[0] == 7


def test_a_refused_trial_is_cached_as_its_reason(tmp_path):
    store = TrialCache(tmp_path / "cache")
    path = make_bad(tmp_path / "bad", "missing_column.csv")
    for _ in range(2):
        with pytest.raises(TrialError, match="missing column") as info:
            load_trial(path, cache=store)
        assert str(path) in str(info.value)
    assert (store.misses, store.hits) == (1, 1)


def test_a_broken_entry_is_a_miss_and_is_rewritten(trial, tmp_path):
    store = TrialCache(tmp_path / "cache")
    load_trial(trial, cache=store)
    (entry,) = store.folder.glob("*.npz")
    entry.write_bytes(b"not a zip file")
    demo = load_trial(trial, cache=store)
    assert (store.misses, store.hits) == (2, 0)
    assert_same_demo(demo, load_trial(trial))
    load_trial(trial, cache=store)
    assert store.hits == 1


def test_an_unwritable_folder_only_costs_the_speed(trial, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    store = TrialCache(blocker / "cache")                # cannot be created
    assert_same_demo(load_trial(trial, cache=store), load_trial(trial))


def test_load_recorded_uses_it_and_reports_each_file(tmp_path):
    root = tmp_path / "data"
    write_csv(root / "reach" / "a.csv", HEADER, trial_rows(seed=1))
    write_csv(root / "reach" / "b.csv", HEADER, trial_rows(seed=2))
    make_bad(root / "reach", "one_row.csv")
    store, calls = TrialCache(tmp_path / "cache"), []
    with pytest.warns(UserWarning):
        demos, skipped = load_recorded(root, cache=store, on_trial=lambda: calls.append(1))
    with pytest.warns(UserWarning):
        again, skipped_again = load_recorded(root, cache=store)
    assert len(calls) == 3 and len(demos) == 2 and skipped == skipped_again
    assert (store.misses, store.hits) == (3, 3)
    for a, b in zip(demos, again, strict=True):
        assert_same_demo(a, b)


def test_clear_and_size(trial, tmp_path):
    store = TrialCache(tmp_path / "cache")
    load_trial(trial, cache=store)
    load_trial(trial, preprocess="causal", cache=store)
    n, size = store.size()
    assert n == 2 and size > 0
    assert store.clear() == 2 and store.size() == (0, 0)


def test_where_it_lives(monkeypatch, tmp_path):
    monkeypatch.setenv("SANDBOX_CACHE_DIR", str(tmp_path / "mine"))
    assert default_folder() == tmp_path / "mine"
    assert TrialCache().folder == tmp_path / "mine"
    monkeypatch.delenv("SANDBOX_CACHE_DIR")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    if cache_module.sys.platform.startswith("linux"):
        assert default_folder() == tmp_path / "xdg" / "handover-sandbox" / "trials"


def test_resolve_and_bad_arguments(tmp_path):
    assert resolve_cache(None) is None and resolve_cache(False) is None
    assert resolve_cache(tmp_path).folder == tmp_path
    store = TrialCache(tmp_path)
    assert resolve_cache(store) is store
    with pytest.raises(ValueError, match="cache: expected a TrialCache"):
        resolve_cache(3)
    with pytest.raises(ValueError, match="cache folder: expected a path"):
        TrialCache(3)


def _parts_trial(folder: Path, shift: float = 0.0) -> None:
    """A trial folder of two part files (hand and robot), no time column."""
    write_csv(folder / "giver_hand.csv", ["x", "y", "z"],
              [[0.01 * i + shift, 0.5, 1.0] for i in range(40)])
    write_csv(folder / "arm.csv", ["j"], [[0.02 * i] for i in range(40)])


def test_a_trial_folder_of_part_files_is_cached_and_keyed_by_each_part(tmp_path):
    spec = DataSpec.from_dict({"rate_hz": 20, "files": {"h": "*_hand.csv", "r": "arm.csv"},
                               "robot": ["r.j"], "modalities": {"hand": {
                                   "columns": ["h.x", "h.y", "h.z"]}}})
    trial = tmp_path / "reach" / "trial0"
    _parts_trial(trial)
    store = TrialCache(tmp_path / "cache")
    fresh = load_trial(trial, spec=spec, preprocess="none")
    load_trial(trial, spec=spec, preprocess="none", cache=store)
    assert_same_demo(load_trial(trial, spec=spec, preprocess="none", cache=store), fresh)
    assert (store.misses, store.hits) == (1, 1)
    _parts_trial(trial, shift=0.1)                           # one part's bytes change: a miss
    changed = load_trial(trial, spec=spec, preprocess="none", cache=store)
    assert (store.misses, store.hits) == (2, 1)
    np.testing.assert_allclose(changed.human[:, 0] - fresh.human[:, 0], 0.1)
    (trial / "other_hand.csv").write_text("x,y,z\n0,0,0\n")  # two files match 'h': no key
    assert store.key(trial, [trial / "arm.csv", tmp_path / "missing.csv"]) is None
    with pytest.raises(TrialError, match="2 files matching"):
        load_trial(trial, spec=spec, preprocess="none", cache=store)
    assert (store.misses, store.hits) == (2, 1)
