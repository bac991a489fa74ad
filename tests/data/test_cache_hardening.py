"""The trial cache cannot be fooled (issue 29, items 1 and 2).

Item 1: the cache hashes a trial file only after checking it is a regular
file within the size limit, so a FIFO, a link to ``/dev/zero``, a folder, a
dangling link or a file over the limit named ``*.csv`` is refused by the
loader with its reason, with the cache on as with it off. Item 2: an entry is
served only if its digest matches its key, its source and its content; any
tampered, truncated, swapped, forged or oversized entry is a miss, the CSV is
read again and the entry rewritten.
"""

from __future__ import annotations

import io
import json
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

from sandbox.data import cache as cache_module
from sandbox.data import limits
from sandbox.data.cache import TrialCache
from sandbox.data.recorded import TrialError, load_recorded, load_trial
from tests.conftest import REPO
from tests.data.test_cache import assert_same_demo
from tests.data.test_recorded import HEADER, trial_rows, write_csv

#: Generous for a loaded 2-core machine: the reproducers used to hang forever.
TIMEOUT_S = 120

posix_only = pytest.mark.skipif(os.name != "posix", reason="FIFOs and /dev/zero are POSIX")


@pytest.fixture
def trial(tmp_path: Path) -> Path:
    return write_csv(tmp_path / "data" / "reach" / "trial1.csv", HEADER, trial_rows())


@pytest.fixture
def store(tmp_path: Path) -> TrialCache:
    return TrialCache(tmp_path / "cache")


# ----------------------------------------------------------------- item 1: special files


def _special(kind: str, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "dev_zero":
        path.symlink_to("/dev/zero")
    elif kind == "folder":
        path.mkdir()
    elif kind == "dangling":
        path.symlink_to(path.parent / "nowhere.csv")
    return path


@posix_only
@pytest.mark.parametrize("cached", [True, False])
@pytest.mark.parametrize("kind", ["fifo", "dev_zero", "folder", "dangling"])
def test_a_special_file_named_csv_is_refused_with_its_reason(tmp_path, kind, cached):
    path = _special(kind, tmp_path / "data" / "reach" / "odd.csv")
    store = TrialCache(tmp_path / "cache") if cached else False
    with pytest.raises(TrialError, match="not a regular file|no such file") as info:
        load_trial(path, cache=store)
    assert str(path) in str(info.value) and "\n" not in str(info.value)
    if cached:
        assert not (tmp_path / "cache").exists() or not list((tmp_path / "cache").iterdir())


@posix_only
@pytest.mark.parametrize("cached", ["", "--no-cache"])
def test_fit_skips_a_fifo_and_a_dev_zero_link_instead_of_hanging(tmp_path, cached):
    """Issue 29 item 1's reproducer: ``fit`` on a folder with a FIFO named ``*.csv``."""
    root = tmp_path / "data"
    for task in ("left", "right"):
        for i in range(3):
            write_csv(root / task / f"t{i}.csv", HEADER, trial_rows(seed=i + 3 * (task == "left")))
    _special("fifo", root / "left" / "fifo.csv")
    _special("dev_zero", root / "right" / "zero.csv")
    env = {**os.environ, "PYTHONPATH": str(REPO), "SANDBOX_CACHE_DIR": str(tmp_path / "cache")}
    args = [sys.executable, "-m", "sandbox", "fit", "--data", str(root), "--out",
            str(tmp_path / "m.npz"), "--verbose", *([cached] if cached else [])]
    done = subprocess.run(args, capture_output=True, text=True, timeout=TIMEOUT_S, env=env,
                          cwd=tmp_path)
    assert "fifo.csv" in done.stderr and "zero.csv" in done.stderr, done.stderr
    assert "not a regular file" in done.stderr and "Traceback" not in done.stderr


def test_a_file_over_the_limit_is_never_hashed(trial, store, monkeypatch):
    monkeypatch.setattr(limits, "MAX_FILE_BYTES", trial.stat().st_size - 1)
    hashed = []
    real = cache_module.hashlib.sha256
    monkeypatch.setattr(cache_module.hashlib, "sha256", lambda *a: hashed.append(a) or real(*a))
    assert store.key(trial) is None
    assert hashed == []                                # checked with fstat, never hashed
    monkeypatch.setattr(limits, "MAX_FILE_BYTES", trial.stat().st_size)
    assert store.key(trial) is not None


def test_a_file_that_is_not_cached_is_not_written_to_the_cache(tmp_path, store, monkeypatch):
    path = write_csv(tmp_path / "data" / "reach" / "big.csv", HEADER, trial_rows())
    monkeypatch.setattr("sandbox.data.trialfile.MAX_FILE_BYTES", 100)
    monkeypatch.setattr(limits, "MAX_FILE_BYTES", 100)
    with pytest.raises(TrialError, match="MAX_FILE_BYTES"):
        load_trial(path, cache=store)
    assert store.size() == (0, 0) and store.misses == 0


# ----------------------------------------------------------------- item 2: tampered entries


def _members(entry: Path) -> dict[str, np.ndarray]:
    with np.load(entry, allow_pickle=False) as z:
        return {k: np.array(z[k]) for k in z.files}


def _write(entry: Path, members: dict[str, np.ndarray]) -> None:
    with open(entry, "wb") as fh:
        np.savez(fh, **members)


def _edit_info(members: dict, **changes) -> dict:
    info = json.loads(str(members["info"]))
    info.update(changes)
    return {**members, "info": np.array(json.dumps(info))}


def _hand_times_1000(m):
    return {**m, "human": m["human"] * 1000}


def _relabelled(m):
    return _edit_info(m, task="other")


def _half_rows(m):
    n = m["times"].shape[0] // 2
    return {**m, **{k: m[k][:n] for k in ("times", "human", "robot", "modality_measured")}}


def _forged_refusal(m):
    info = json.loads(str(m["info"]))
    return {"info": np.array(json.dumps({"key": info["key"], "path": info["path"],
                                         "error": "forged: refused"})),
            "digest": m["digest"]}


def _no_digest(m):
    return {k: v for k, v in m.items() if k != "digest"}


@pytest.mark.parametrize("tamper", [_hand_times_1000, _relabelled, _half_rows, _forged_refusal,
                                    _no_digest])
def test_an_edited_entry_is_never_served(trial, store, tamper, capsys):
    fresh = load_trial(trial)
    load_trial(trial, cache=store)
    (entry,) = store.folder.glob("*.npz")
    _write(entry, tamper(_members(entry)))
    store.verbose = True
    again = load_trial(trial, cache=store)
    assert_same_demo(again, fresh)
    assert (store.misses, store.hits) == (2, 0)
    assert f"cache: entry {entry} not used" in capsys.readouterr().err
    assert_same_demo(load_trial(trial, cache=store), fresh)    # rewritten: a hit again
    assert store.hits == 1


def test_another_trials_entry_copied_over_is_a_miss(tmp_path, store):
    a = write_csv(tmp_path / "data" / "reach" / "a.csv", HEADER, trial_rows(seed=1))
    b = write_csv(tmp_path / "data" / "reach" / "b.csv", HEADER, trial_rows(seed=2))
    other = TrialCache(tmp_path / "other")
    load_trial(a, cache=store)
    load_trial(b, cache=other)
    (entry_a,), (entry_b,) = store.folder.glob("*.npz"), other.folder.glob("*.npz")
    entry_a.write_bytes(entry_b.read_bytes())         # b's valid entry under a's name
    assert_same_demo(load_trial(a, cache=store), load_trial(a))
    assert store.hits == 0


def _truncated(data: bytes) -> bytes:
    return data[: len(data) // 2]


def _crc_damaged(data: bytes) -> bytes:
    i = len(data) // 3
    return data[:i] + bytes([data[i] ^ 0xFF]) + data[i + 1:]


@pytest.mark.parametrize("damage", [_truncated, _crc_damaged, lambda d: b"", lambda d: b"PK"])
def test_a_damaged_entry_is_a_miss_and_the_csv_is_read_again(trial, store, damage):
    load_trial(trial, cache=store)
    (entry,) = store.folder.glob("*.npz")
    entry.write_bytes(damage(entry.read_bytes()))
    assert_same_demo(load_trial(trial, cache=store), load_trial(trial))
    assert (store.misses, store.hits) == (2, 0)


def _npy_header(shape: tuple[int, ...]) -> bytes:
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, {"descr": "<f8", "fortran_order": False,
                                               "shape": shape})
    return buf.getvalue()


@pytest.mark.parametrize("member", ["huge_header", "deflated"])
def test_an_entry_declaring_a_huge_array_is_a_miss_without_allocating_it(trial, store, member):
    load_trial(trial, cache=store)
    (entry,) = store.folder.glob("*.npz")
    members = _members(entry)
    with zipfile.ZipFile(entry, "w", zipfile.ZIP_DEFLATED) as z:
        for name, value in members.items():
            if name == "human":
                continue
            buf = io.BytesIO()
            np.lib.format.write_array(buf, value, allow_pickle=False)
            z.writestr(f"{name}.npy", buf.getvalue())
        if member == "huge_header":        # declares 8 TB, holds a few bytes
            z.writestr("human.npy", _npy_header((10**12, 3)) + b"\0" * 64)
        else:                              # 256 MiB of zeros, deflated to ~256 kB
            with z.open("human.npy", "w", force_zip64=True) as fh:
                fh.write(_npy_header((2**25,)))
                block = b"\0" * 2**24
                for _ in range(16):
                    fh.write(block)
    assert_same_demo(load_trial(trial, cache=store), load_trial(trial))
    assert store.hits == 0


@pytest.mark.skipif(os.name != "posix", reason="symlinks")
def test_a_link_entry_is_a_miss(trial, store, tmp_path):
    load_trial(trial, cache=store)
    (entry,) = store.folder.glob("*.npz")
    kept = tmp_path / "kept.npz"
    entry.rename(kept)
    entry.symlink_to(kept)                 # the same bytes, but not a regular file
    assert_same_demo(load_trial(trial, cache=store), load_trial(trial))
    assert store.hits == 0 and not entry.is_symlink()


def test_a_folder_named_like_an_entry_is_a_miss_and_clear_survives_it(trial, store):
    load_trial(trial, cache=store)
    (entry,) = store.folder.glob("*.npz")
    entry.unlink()
    entry.mkdir()
    assert_same_demo(load_trial(trial, cache=store), load_trial(trial))
    assert store.hits == 0
    assert store.clear() == 0 and entry.is_dir()


def test_load_recorded_keeps_every_trial_when_entries_are_damaged(tmp_path, store):
    root = tmp_path / "data"
    for i in range(3):
        write_csv(root / "reach" / f"t{i}.csv", HEADER, trial_rows(seed=i))
    first, _ = load_recorded(root, cache=store)
    for entry in store.folder.glob("*.npz"):
        entry.write_bytes(entry.read_bytes()[:100])
    again, skipped = load_recorded(root, cache=store)
    assert skipped == [] and len(again) == len(first) == 3
    for a, b in zip(first, again, strict=True):
        assert_same_demo(a, b)
