"""Progress on stderr for the long commands: tqdm bars and one-line status messages.

Everything goes to stderr, so a command's stdout (its summary, JSON) stays
clean, and only when stderr is a terminal, so logs and captured output hold
the results and the errors, not bar redraws. ``enabled=False`` (the
commands' ``--no-progress``) writes nothing anywhere.
"""

from __future__ import annotations

import os
import sys


def bar(total: int, desc: str, enabled: bool, unit: str = "trial"):
    """A tqdm bar of ``total`` steps on stderr, drawn at once (0 done); a no-op when disabled."""
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit=unit, disable=not shown(enabled), file=sys.stderr,
                mininterval=0.25, **_size())


def status(message: str, enabled: bool) -> None:
    """Print ``message`` on stderr at once when enabled."""
    if shown(enabled):
        print(message, file=sys.stderr, flush=True)


def shown(enabled: bool) -> bool:
    """Whether progress is drawn: asked for, and stderr is a terminal."""
    return bool(enabled) and sys.stderr.isatty()


def _size() -> dict:
    """tqdm's width and height where stderr's terminal has no size (a fresh
    pseudo-terminal says 0 x 0, and tqdm would then draw nothing)."""
    try:
        size = os.get_terminal_size(sys.stderr.fileno())
    except (OSError, ValueError):
        return {}
    return {} if size.columns and size.lines else {"ncols": 80, "nrows": 24}
