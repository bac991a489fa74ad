"""Folders of recording sessions: ``<root>/<session>/<task>/<trial>.csv``.

A session is one set in the shared per-trial layout (``<session>/<task>/<trial>.csv``,
:func:`sandbox.data.recorded.find_trials`): one sitting, one tracker calibration,
one subject. A folder of sessions holds several of them side by side, and
``python -m sandbox evaluate`` runs leave-one-session-out on it
(:mod:`sandbox.eval.crosssession`). :func:`find_sessions` tells the two layouts
apart by where the trial files are:

* a set: the subfolders (tasks) hold the ``.csv`` files;
* a folder of sessions: the subfolders' subfolders (each session's tasks) hold them;
* both kinds side by side is an error naming what was found.

Subfolders that hold no ``.csv`` file at either depth are ignored, as
:func:`~sandbox.data.recorded.find_trials` ignores empty task folders.

Examples
--------
>>> import tempfile
>>> from pathlib import Path
>>> root = Path(tempfile.mkdtemp())
>>> for name in ("monday/up/001.csv", "tuesday/up/001.csv", "tuesday/down/001.csv"):
...     (root / name).parent.mkdir(parents=True, exist_ok=True)
...     _ = (root / name).write_text("t\\n")
>>> [p.name for p in find_sessions(root)], find_sessions(root / "monday")
(['monday', 'tuesday'], [])
"""

from __future__ import annotations

from os import PathLike
from pathlib import Path

#: The layout of a set, as the messages name it.
SET_LAYOUT = "<root>/<task>/<trial>.csv"
#: The layout of a folder of sessions, as the messages name it.
SESSIONS_LAYOUT = "<root>/<session>/<task>/<trial>.csv"


def _holds_csv(folder: Path) -> bool:
    return any(p.is_file() for p in folder.glob("*.csv"))


def find_sessions(root: str | PathLike, option: str = "data") -> list[Path]:
    """The session folders of ``root`` sorted by name, or ``[]`` if ``root`` is one set.

    Parameters
    ----------
    root : str or path-like
        A folder in the layout :data:`SET_LAYOUT` or :data:`SESSIONS_LAYOUT`.
    option : str
        What the error messages call ``root`` (e.g. ``"--data"``).

    Returns
    -------
    list of Path
        ``root/<session>`` for every subfolder whose own subfolders hold trial
        files (``[]`` when the subfolders hold the files themselves: a set).

    Raises
    ------
    ValueError
        ``root`` is not a folder, or it holds task folders and session folders
        side by side (a subfolder holding trial files at both depths counts as
        both); the message names them.
    """
    if not isinstance(root, (str, PathLike)):
        raise ValueError(f"{option}: expected a folder, got {root!r}")
    root = Path(root)
    if not root.is_dir():
        raise ValueError(f"{option}: expected a folder {SET_LAYOUT} or {SESSIONS_LAYOUT}, "
                         f"got {str(root)!r}")
    tasks, sessions = [], []
    for child in sorted(p for p in root.iterdir() if p.is_dir()):
        if _holds_csv(child):
            tasks.append(child.name)
        if any(_holds_csv(sub) for sub in child.iterdir() if sub.is_dir()):
            sessions.append(child)
    if tasks and sessions:
        raise ValueError(f"{option}: expected task folders ({SET_LAYOUT}) or session folders "
                         f"({SESSIONS_LAYOUT}), got both in {str(root)!r}: trial files in "
                         f"{tasks} and task folders in {[p.name for p in sessions]}")
    return sessions


def check_sessions(root: str | PathLike, option: str = "data") -> list[Path]:
    """:func:`find_sessions`, which must find at least two sessions (one to leave out and
    one to fit on); ``ValueError`` otherwise."""
    sessions = find_sessions(root, option)
    if len(sessions) < 2:
        found = f"1 ({sessions[0].name})" if sessions else "none (a set of tasks)"
        raise ValueError(f"{option}: expected at least 2 sessions {SESSIONS_LAYOUT} to leave "
                         f"one out, got {found} in {str(root)!r}")
    return sessions
