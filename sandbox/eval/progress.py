"""Progress on stderr for the long commands: tqdm bars and one-line status messages.

Everything goes to stderr, so a command's stdout (its summary, JSON) stays
clean; ``enabled=False`` (the commands' ``--no-progress``) writes nothing.
"""

from __future__ import annotations

import sys


def bar(total: int, desc: str, enabled: bool, unit: str = "trial"):
    """A tqdm bar of ``total`` steps on stderr, drawn at once (0 done); a no-op when disabled."""
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit=unit, disable=not enabled, file=sys.stderr,
                mininterval=0.25, dynamic_ncols=True)


def status(message: str, enabled: bool) -> None:
    """Print ``message`` on stderr at once when enabled."""
    if enabled:
        print(message, file=sys.stderr, flush=True)
