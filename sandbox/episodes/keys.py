"""Keys from a terminal (or any file descriptor): character mode, non-blocking reads.

:class:`Keyboard` switches a terminal to character mode (no Enter needed; Ctrl-C
still interrupts) for the teleop loop (:mod:`sandbox.episodes.keyboard`) and
reads the keys typed since the last call; :func:`split_keys` drops escape
sequences (arrows...).
"""

from __future__ import annotations

import os
import select
import sys
import time
from typing import Any


def split_keys(data: str) -> list[str]:
    """Keys in a chunk of terminal input; escape sequences (arrows...) are dropped."""
    keys, i = [], 0
    while i < len(data):
        if data[i] == "\x1b":  # ESC [ X  or  ESC O X
            i += 3 if data[i + 1:i + 2] in ("[", "O") else 1
            continue
        keys.append(data[i])
        i += 1
    return keys


class Keyboard:
    """Non-blocking key reader on a file descriptor (the terminal in character mode).

    Parameters
    ----------
    fd : int
        File descriptor to read (default: standard input).

    Attributes
    ----------
    closed : bool
        End of input reached (e.g. a pipe that was closed).
    """

    def __init__(self, fd: int | None = None) -> None:
        self.fd = sys.stdin.fileno() if fd is None else fd
        self.closed = False
        self._saved: list[Any] | None = None

    def __enter__(self) -> Keyboard:
        if os.isatty(self.fd):
            import termios
            import tty

            self._saved = termios.tcgetattr(self.fd)
            tty.setcbreak(self.fd)  # keys without Enter, no echo; Ctrl-C still interrupts
        return self

    def __exit__(self, *exc) -> None:
        if self._saved is not None:
            import termios

            termios.tcsetattr(self.fd, termios.TCSADRAIN, self._saved)

    def read(self, timeout: float = 0.0) -> list[str]:
        """Keys typed since the last call (waits up to ``timeout`` s for the first one)."""
        if self.closed:
            time.sleep(timeout)
            return []
        ready, _, _ = select.select([self.fd], [], [], timeout)
        if not ready:
            return []
        data = os.read(self.fd, 1024)
        if not data:
            self.closed = True
            return []
        return split_keys(data.decode("utf-8", "replace"))
