"""Output files of the commands: ``--force``, checked before any work, written whole.

Every command that writes files refuses to replace an existing one unless
``--force`` is given, and says so before it starts working (the paths'
folders are checked by the argparse types of :mod:`sandbox.commands._types`).
Text files are written to a temporary file in the same folder and renamed, so
an interrupted or failed command leaves either the old file or the new one,
never half of it.
"""

from __future__ import annotations

import argparse
import os
import tempfile
from collections.abc import Iterable
from pathlib import Path

#: Files :func:`sandbox.eval.plots.plot_report` writes into its folder (one report).
REPORT_FIGURES = ("direct.png", "comparative.png", "recognition.png")
#: The figure it adds when a second report is compared.
COMPARISON_FIGURE = "average_comparison.png"


def add_force(parser: argparse.ArgumentParser, what: str = "output files") -> None:
    """Add ``--force`` (overwrite ``what`` if it exists)."""
    parser.add_argument("--force", action="store_true", help=f"overwrite {what} if it exists")


def check_new(outputs: Iterable[tuple[str, str | Path | None]], force: bool) -> None:
    """``ValueError`` naming the option if one of ``(option, path)`` exists and not ``force``."""
    if force:
        return
    for option, path in outputs:
        if path is not None and Path(path).exists():
            raise ValueError(f"{option}: {path} exists; pass --force to overwrite it")


def figures(folder: str | Path | None, compare: bool = False) -> list[Path]:
    """The figure files a report's plots write into ``folder`` (none if no folder)."""
    if folder is None:
        return []
    names = REPORT_FIGURES + ((COMPARISON_FIGURE,) if compare else ())
    return [Path(folder) / n for n in names]


def check_folder(option: str, folder: str | Path, force: bool) -> None:
    """``ValueError`` if ``folder`` holds files and not ``force`` (a fresh folder is fine)."""
    path = Path(folder)
    if not force and path.is_dir() and any(path.iterdir()):
        raise ValueError(f"{option}: {path} is not empty; pass --force to write into it")


def write_text(path: str | Path, text: str) -> Path:
    """Write ``text`` to ``path`` whole: a temporary file beside it, then a rename (its
    missing folders are made first)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent or ".")
    try:
        with os.fdopen(handle, "w", encoding="utf-8") as file:
            file.write(text)
        os.chmod(temporary, 0o666 & ~_umask())   # mkstemp's file is private (0600)
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise
    return path


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
