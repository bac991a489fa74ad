"""An on-disk cache of loaded and preprocessed trials.

Loading a recorded trial reads its CSV file, checks it and runs the hand
filter (and, for training demos, the smoother) over every tracked point.
:class:`TrialCache` keeps the result, one ``.npz`` file per trial and
loading, so the next evaluation, fit or sweep of the same data skips all of
that. What a cached entry was made from is its key (:meth:`TrialCache.key`):

* the file's bytes (SHA-256), its path and its task label; the file is hashed
  only if it is a regular file within ``MAX_FILE_BYTES`` (checked on the open
  file, read no further than that limit plus one byte): anything else has no
  key and goes straight to the loader, which refuses it with its reason. A
  trial folder of a spec's ``files`` (one file per part) is keyed by the name
  and bytes of each of its part files, under the same rules;
* what was asked of the loader: the spec's columns and modalities, the
  observed modalities, the preprocessing mode and options, the longest duration;
* the package version and the source code of the modules that load and
  preprocess (so a changed filter never reuses stale trials).

A trial the loader refuses is cached too, as its one-line reason. Entries are
written atomically (a temporary file, then a rename) and read without pickle.
Each entry holds a SHA-256 digest of its key, its source file's path, its
metadata and its arrays (dtype, shape and bytes); an entry is served only if
it is a regular file (``lstat``: no link, FIFO or device) within the limits of
model files (:mod:`sandbox.core.archive`: file size, members, each member's
declared size checked before it is read), its members have the shapes its
metadata implies, and the digest matches its name and source. Anything else
(an edited, relabelled, truncated, swapped or forged entry, a damaged
archive) is a miss: the CSV is read again and the entry rewritten; with
``verbose=True`` (the commands' ``--verbose``) each such entry is named on
standard error with the reason. The digest detects accidents and edits made
without this module; it is not a signature (whoever can write the folder can
also recompute it). The folder is safe to delete at any time
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
import stat
import sys
import tempfile
from collections.abc import Sequence
from dataclasses import asdict, is_dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from sandbox.core.modality import Modality
from sandbox.data.demonstration import Demonstration

#: Bumped when the layout of an entry changes.
FORMAT = 2
#: Modules whose source is part of every key.
_CODE = ("cache", "demonstration", "filtering", "glitches", "kalman", "limits", "preprocess",
         "recorded", "segment", "signals", "spec", "spec_frame", "spec_layout", "spec_read",
         "trialfile")
_ARRAYS = ("times", "human", "robot", "modality_measured")
#: Bytes hashed per read of a source file.
_CHUNK = 2**20


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

    def __init__(self, folder: str | Path | None = None, *, verbose: bool = False) -> None:
        if folder is not None and not isinstance(folder, (str, os.PathLike)):
            raise ValueError(f"cache folder: expected a path, got {folder!r}")
        self.folder = Path(folder) if folder is not None else default_folder()
        self.verbose = bool(verbose)
        self.hits = 0
        self.misses = 0

    def key(self, path: Path, members: Sequence[Path] | None = None,
            **asked: Any) -> str | None:
        """The entry name of ``path`` loaded with the options ``asked``.

        None, without reading it, if ``path`` is not a regular file within
        :data:`~sandbox.data.limits.MAX_FILE_BYTES` (a folder, FIFO, device,
        dangling link, a file too large or that cannot be opened): such a file
        is the loader's to refuse, and is never cached. A trial folder of the
        spec's ``files`` (``path`` a folder) gives its part files as ``members``:
        it is keyed by each one's name and bytes, and has no key if any has none.
        """
        if members is None:
            h = _file_digest(Path(path))
        else:
            h = hashlib.sha256(b"members")
            for member in members:
                part = _file_digest(Path(member))
                if part is None:
                    return None
                h.update(f"{Path(member).name}\0{part.hexdigest()}\0".encode())
        if h is None:
            return None
        h.update(json.dumps({"path": str(path), "code": _code_digest(),
                             **{k: _plain(v) for k, v in sorted(asked.items())}},
                            sort_keys=True, default=repr).encode())
        return h.hexdigest()[:40]

    def get(self, key: str, source: str | Path | None = None) -> Demonstration | str | None:
        """The cached trial, the reason it was refused (str), or None (not cached).

        ``source`` is the trial file the entry must have been made from. An
        entry that cannot be read, or whose digest does not match its key,
        source and content, is a miss (named on stderr if ``verbose``).
        """
        file = self.folder / f"{key}.npz"
        try:
            found = _read_entry(file, key, None if source is None else str(source))
        except FileNotFoundError:
            self.misses += 1
            return None
        except Exception as error:  # noqa: BLE001 - any failure to read an entry is a miss
            self.misses += 1
            if self.verbose:
                print(f"cache: entry {file} not used ({_reason(error)}); reading "
                      f"{source if source is not None else 'the trial'} again", file=sys.stderr)
            return None
        self.hits += 1
        return found

    def put(self, key: str, found: Demonstration | str,
            source: str | Path | None = None) -> None:
        """Keep a loaded trial, or the reason it was refused; a write error is ignored."""
        info: dict[str, Any] = {"key": key, "path": None if source is None else str(source)}
        if isinstance(found, str):
            info["error"] = found
            arrays: dict[str, np.ndarray] = {}
        else:
            info.update(_info(found))
            arrays = {k: np.asarray(getattr(found, k)) for k in _ARRAYS[:3]}
            arrays["modality_measured"] = np.asarray(found.meta["modality_measured"])
        members: dict[str, Any] = {"info": np.array(json.dumps(info)),
                                   "digest": np.array(_digest(key, info, arrays)), **arrays}
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(dir=self.folder, suffix=".tmp")
            with os.fdopen(fd, "wb") as f:
                np.savez(f, **members)
            os.replace(tmp, self.folder / f"{key}.npz")
        except OSError:
            return

    def clear(self) -> int:
        """Delete every entry; returns how many there were (what cannot be deleted stays)."""
        n = 0
        for file in [*self.folder.glob("*.npz"), *self.folder.glob("*.tmp")]:
            try:
                file.unlink(missing_ok=True)
            except OSError:
                continue
            n += file.suffix == ".npz"
        return n

    def size(self) -> tuple[int, int]:
        """Number of entries and their total size (bytes; of the links themselves for links)."""
        sizes = []
        for file in self.folder.glob("*.npz"):
            try:
                sizes.append(file.lstat().st_size)
            except OSError:
                continue
        return len(sizes), sum(sizes)


def _file_digest(path: Path) -> Any:
    """SHA-256 (a ``hashlib`` object) of a regular file within ``MAX_FILE_BYTES``, else None.

    The type is checked before the file is opened (a FIFO would block the
    open) and again on the open file (it may have changed in between); no
    more than ``MAX_FILE_BYTES + 1`` bytes are read.
    """
    from sandbox.data.limits import MAX_FILE_BYTES

    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0)
    try:
        if not stat.S_ISREG(os.stat(path).st_mode):
            return None
        fd = os.open(path, flags)
    except (OSError, ValueError):
        return None
    try:
        with os.fdopen(fd, "rb") as fh:
            opened = os.fstat(fh.fileno())
            if not stat.S_ISREG(opened.st_mode) or opened.st_size > MAX_FILE_BYTES:
                return None
            h, left = hashlib.sha256(), MAX_FILE_BYTES + 1
            while left > 0 and (chunk := fh.read(min(_CHUNK, left))):
                h.update(chunk)
                left -= len(chunk)
    except OSError:
        return None
    return h if left > 0 else None


def _read_entry(file: Path, key: str, source: str | None) -> Demonstration | str:
    """The trial or refusal of entry ``file`` after checking it (any failure raises)."""
    from sandbox.core.archive import open_archive, read_array
    from sandbox.core.limits import MAX_METADATA_BYTES

    if not stat.S_ISREG(os.lstat(file).st_mode):
        raise ValueError("not a regular file")
    with open_archive(file) as archive:
        info = json.loads(str(read_array(archive, "info", "U", (), MAX_METADATA_BYTES)))
        stored = str(read_array(archive, "digest", "U", (), 1024))
        if not isinstance(info, dict):
            raise ValueError("its metadata is not a mapping")
        arrays = {} if "error" in info else _arrays(archive, info)
    if info.get("key") != key or (source is not None and info.get("path") != source):
        raise ValueError("made for another trial or options")
    if stored != _digest(key, info, arrays):
        raise ValueError("its digest does not match its content")
    return str(info["error"]) if "error" in info else _demo(arrays, info)


def _arrays(archive: Any, info: dict) -> dict[str, np.ndarray]:
    """The arrays of a trial entry, each checked against the shapes its metadata implies."""
    from sandbox.core.archive import read_array

    p, q, m = len(info["human_names"]), len(info["robot_names"]), len(info["modalities"])
    times = read_array(archive, "times", "f", (None,))
    n = times.shape[0]
    return {"times": times, "human": read_array(archive, "human", "f", (n, p)),
            "robot": read_array(archive, "robot", "f", (n, q)),
            "modality_measured": read_array(archive, "modality_measured", "b", (n, m))}


def _digest(key: str, info: dict, arrays: dict[str, np.ndarray]) -> str:
    """SHA-256 of an entry's key, metadata (with its source) and arrays (dtype, shape, bytes)."""
    h = hashlib.sha256(f"{FORMAT} {key}".encode())
    h.update(json.dumps(info, sort_keys=True).encode())
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name} {a.dtype.str} {a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _reason(error: BaseException) -> str:
    """One line: the error's message, or its type when it has none."""
    text = " ".join(str(error).split())
    return text[:200] if text else type(error).__name__


def _info(demo: Demonstration) -> dict:
    return {"task": demo.task, "source": demo.source, "human_names": list(demo.human_names),
            "robot_names": list(demo.robot_names), "robot_space": demo.robot_space,
            "modalities": [[m.name, list(m.dims), m.kind, m.units] for m in demo.modalities],
            "report": demo.meta["report"]}


def _demo(z: dict[str, np.ndarray], info: dict) -> Demonstration:
    from sandbox.data.preprocess import measured_meta

    measured = np.array(z["modality_measured"], dtype=bool)
    return Demonstration(
        times=z["times"], human=z["human"], robot=z["robot"], task=info["task"],
        human_names=tuple(info["human_names"]), robot_names=tuple(info["robot_names"]),
        modalities=tuple(Modality(n, tuple(d), k, u) for n, d, k, u in info["modalities"]),
        source=info["source"], meta={"report": info["report"], **measured_meta(measured)},
        robot_space=info.get("robot_space", "joint"))


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
