"""An on-disk cache of loaded and preprocessed trials.

Loading a recorded trial reads its CSV file, checks it and runs the hand
filter (and, for training demos, the smoother) over every tracked point.
:class:`TrialCache` keeps the result, one ``.npz`` file per trial and
loading, so the next evaluation, fit or sweep of the same data skips all of
that. What a cached entry was made from is its key (:meth:`TrialCache.key`):

* the file's bytes (SHA-256), its path and its task label;
* what was asked of the loader: the spec's columns and modalities, the
  observed modalities, the preprocessing mode and options, the longest duration;
* the package version and the source code of the modules that load and
  preprocess (so a changed filter never reuses stale trials).

A trial the loader refuses is cached too, as its one-line reason. Entries are
written atomically (a temporary file, then a rename) and read without pickle;
an unreadable entry is a miss. The folder is safe to delete at any time
(``python -m sandbox data cache --clear``); ``--no-cache`` on the commands
bypasses it. Where it lives: ``$SANDBOX_CACHE_DIR`` if set, else the user's
cache directory (``$XDG_CACHE_HOME`` or ``~/.cache`` on Linux,
``~/Library/Caches`` on macOS, ``%LOCALAPPDATA%`` on Windows) under
``handover-sandbox/trials``.
"""

from __future__ import annotations

import hashlib
import json
import os
import sys
import tempfile
from dataclasses import asdict, is_dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from sandbox.core.modality import Modality
from sandbox.data.demonstration import Demonstration

#: Bumped when the layout of an entry changes.
FORMAT = 1
#: Modules whose source is part of every key.
_CODE = ("cache", "demonstration", "filtering", "glitches", "kalman", "limits", "preprocess",
         "recorded", "signals", "spec", "trialfile")
_ARRAYS = ("times", "human", "robot", "modality_measured")


def default_folder() -> Path:
    """Where the cache lives (see the module docstring)."""
    if os.environ.get("SANDBOX_CACHE_DIR"):
        return Path(os.environ["SANDBOX_CACHE_DIR"])
    if sys.platform == "darwin":
        base = Path.home() / "Library" / "Caches"
    elif os.name == "nt":
        base = Path(os.environ.get("LOCALAPPDATA", Path.home() / "AppData" / "Local"))
    else:
        base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "handover-sandbox" / "trials"


@lru_cache(maxsize=1)
def _code_digest() -> str:
    from sandbox import __version__

    h = hashlib.sha256(f"{FORMAT} {__version__}".encode())
    here = Path(__file__).parent
    for name in _CODE:
        h.update((here / f"{name}.py").read_bytes())
    return h.hexdigest()


def _plain(value: Any) -> Any:
    """A JSON-ready version of an option value (dataclasses as dicts)."""
    if is_dataclass(value) and not isinstance(value, type):
        return {"type": type(value).__name__, **asdict(value)}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in sorted(value.items())}
    return value


class TrialCache:
    """Loaded trials kept on disk, keyed by their file's content and the loading options.

    Parameters
    ----------
    folder : str or Path, optional
        Where the entries go (default :func:`default_folder`); created on the
        first write.

    Attributes
    ----------
    hits, misses : int
        Lookups answered from the folder, and not.
    """

    def __init__(self, folder: str | Path | None = None) -> None:
        if folder is not None and not isinstance(folder, (str, os.PathLike)):
            raise ValueError(f"cache folder: expected a path, got {folder!r}")
        self.folder = Path(folder) if folder is not None else default_folder()
        self.hits = 0
        self.misses = 0

    def key(self, path: Path, **asked: Any) -> str:
        """The entry name of ``path`` loaded with the options ``asked``."""
        h = hashlib.sha256(Path(path).read_bytes())
        h.update(json.dumps({"path": str(path), "code": _code_digest(),
                             **{k: _plain(v) for k, v in sorted(asked.items())}},
                            sort_keys=True, default=repr).encode())
        return h.hexdigest()[:40]

    def get(self, key: str) -> Demonstration | str | None:
        """The cached trial, the reason it was refused (str), or None (not cached)."""
        file = self.folder / f"{key}.npz"
        try:
            with np.load(file, allow_pickle=False) as z:
                info = json.loads(str(z["info"]))
                found = info["error"] if "error" in info else _demo(z, info)
        except (OSError, ValueError, KeyError, TypeError):
            self.misses += 1
            return None
        self.hits += 1
        return found

    def put(self, key: str, found: Demonstration | str) -> None:
        """Keep a loaded trial, or the reason it was refused; a write error is ignored."""
        if isinstance(found, str):
            arrays = {"info": np.array(json.dumps({"error": found}))}
        else:
            arrays = {"info": np.array(json.dumps(_info(found)))}
            arrays.update({k: np.asarray(getattr(found, k)) for k in _ARRAYS[:3]})
            arrays["modality_measured"] = np.asarray(found.meta["modality_measured"])
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(dir=self.folder, suffix=".tmp")
            with os.fdopen(fd, "wb") as f:
                np.savez(f, **arrays)
            os.replace(tmp, self.folder / f"{key}.npz")
        except OSError:
            return

    def clear(self) -> int:
        """Delete every entry; returns how many there were."""
        n = 0
        for file in self.folder.glob("*.npz"):
            file.unlink(missing_ok=True)
            n += 1
        for file in self.folder.glob("*.tmp"):
            file.unlink(missing_ok=True)
        return n

    def size(self) -> tuple[int, int]:
        """Number of entries and their total size (bytes)."""
        files = list(self.folder.glob("*.npz"))
        return len(files), sum(f.stat().st_size for f in files)


def _info(demo: Demonstration) -> dict:
    return {"task": demo.task, "source": demo.source, "human_names": list(demo.human_names),
            "robot_names": list(demo.robot_names),
            "modalities": [[m.name, list(m.dims), m.kind, m.units] for m in demo.modalities],
            "report": demo.meta["report"]}


def _demo(z, info: dict) -> Demonstration:
    from sandbox.data.preprocess import measured_meta

    measured = np.array(z["modality_measured"], dtype=bool)
    return Demonstration(
        times=z["times"], human=z["human"], robot=z["robot"], task=info["task"],
        human_names=tuple(info["human_names"]), robot_names=tuple(info["robot_names"]),
        modalities=tuple(Modality(n, tuple(d), k, u) for n, d, k, u in info["modalities"]),
        source=info["source"], meta={"report": info["report"], **measured_meta(measured)})


def resolve_cache(cache: TrialCache | bool | str | Path | None) -> TrialCache | None:
    """``True``: the default cache; a path: a cache there; ``False``/``None``: none."""
    if cache is None or cache is False:
        return None
    if cache is True:
        return TrialCache()
    if isinstance(cache, TrialCache):
        return cache
    if isinstance(cache, (str, os.PathLike)):
        return TrialCache(cache)
    raise ValueError(f"cache: expected a TrialCache, a folder, True or False, got {cache!r}")
