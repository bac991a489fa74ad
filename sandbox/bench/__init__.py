"""Benchmarks behind ``python -m sandbox bench`` (medians of repeated runs, in one process)."""

from __future__ import annotations

import json
import os
import sys


def restart_single_threaded(module: str) -> None:
    """Re-exec ``python -m module`` with this process's arguments and one BLAS thread,
    unless ``OPENBLAS_NUM_THREADS`` is already 1 (the limit is read at numpy import)."""
    if os.environ.get("OPENBLAS_NUM_THREADS") == "1":
        return
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    os.execve(sys.executable, [sys.executable, "-m", module, *sys.argv[1:]], env)


def print_result(result: dict, as_json: bool, width: int) -> None:
    """Print benchmark figures as one JSON object or as aligned ``key value`` lines."""
    if as_json:
        print(json.dumps(result, indent=2))
    else:
        _print_lines(result, width, "")


def _print_lines(result: dict, width: int, indent: str) -> None:
    """``key value`` lines; a section (a mapping of mappings, e.g. the roofline) is indented."""
    for key, value in result.items():
        if isinstance(value, dict) and any(isinstance(v, dict) for v in value.values()):
            print(f"{indent}{key}")
            _print_lines(value, width - 2, indent + "  ")
        else:
            print(f"{indent}{key:{width}s} {value}")
