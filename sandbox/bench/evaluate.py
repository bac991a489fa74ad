"""Benchmark of ``python -m sandbox evaluate``: wall time cold and warm, and the first progress.

``python -m sandbox.bench.evaluate --data DIR [--repeats N] [--json]`` runs the
full default evaluation as a user does, in a subprocess whose stderr is a
pseudo-terminal (so the progress bars are drawn, as in a shell):

* ``cold``: an empty trial cache (every file read, filtered and smoothed);
* ``warm``: the cache that run filled (the researcher's loop: change an
  option, run again).

It reports, per case, the median over ``--repeats`` runs of the wall time
(s), of the leave-one-out's own ``runtime_s`` and of the time from the start
to the first progress output on stderr, with the machine's core count and
load average: on a shared machine the figures follow the load.
"""

from __future__ import annotations

import argparse
import os
import pty
import re
import select
import subprocess
import sys
import tempfile
import time

import numpy as np

from sandbox.bench import print_result


def read_terminal(master: int, proc: subprocess.Popen, *, poll: float = 0.05,
                  on_chunk=None, timeout: float | None = None) -> bytes:
    """Everything written to the pseudo-terminal ``master`` until it closes, or
    until ``proc`` has exited and nothing more comes within ``poll`` seconds.

    ``on_chunk(bytes)`` sees each chunk as it arrives (e.g. to time the first one).
    After ``timeout`` seconds (if given) it raises ``TimeoutError``.
    """
    out, deadline = b"", None if timeout is None else time.monotonic() + timeout
    while True:
        if deadline is not None and time.monotonic() > deadline:
            raise TimeoutError(f"the terminal was still open after {timeout} s: {out[-300:]!r}")
        if not select.select([master], [], [], poll)[0]:
            if proc.poll() is not None:
                return out
            continue
        try:
            chunk = os.read(master, 65536)
        except OSError:       # the other end closed (Linux reports EIO)
            return out
        if not chunk:
            return out
        if on_chunk is not None:
            on_chunk(chunk)
        out += chunk


def run_once(data: str, cache_dir: str, workers: int, n_per_task: int | None = None) -> dict:
    """One ``evaluate`` of ``data``: wall, first-progress and leave-one-out times (s)."""
    with tempfile.TemporaryDirectory() as out:
        cmd = [sys.executable, "-m", "sandbox", "evaluate", "--data", data, "--workers",
               str(workers), "--out", os.path.join(out, "report.json")]
        if n_per_task is not None:
            cmd += ["--n-per-task", str(n_per_task)]
        env = {**os.environ, "SANDBOX_CACHE_DIR": cache_dir}
        master, slave = pty.openpty()
        start = time.perf_counter()
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=slave, env=env)
        os.close(slave)
        first: list[float] = []

        def seen(chunk: bytes) -> None:
            if not first and chunk.strip():
                first.append(time.perf_counter() - start)

        err = read_terminal(master, proc, on_chunk=seen)
        out_text = proc.communicate()[0].decode()
        wall = time.perf_counter() - start
        os.close(master)
    if proc.returncode != 0:
        raise RuntimeError(f"evaluate failed ({proc.returncode}): {err.decode()[-500:]}")
    found = re.search(r"(\d+) trials in ([0-9.]+) s", out_text)
    return {"wall_s": wall, "first_progress_s": first[0] if first else None,
            "loocv_runtime_s": float(found.group(2)) if found else None,
            "trials": int(found.group(1)) if found else None}


def run(data: str, repeats: int = 1, workers: int = 2, n_per_task: int | None = None) -> dict:
    """Cold then warm runs, ``repeats`` times each (alternating), medians."""
    runs: dict[str, list[dict]] = {"cold": [], "warm": []}
    load_before = os.getloadavg()[0]
    for _ in range(repeats):
        with tempfile.TemporaryDirectory() as cache:
            runs["cold"].append(run_once(data, cache, workers, n_per_task))
            runs["warm"].append(run_once(data, cache, workers, n_per_task))
    result = {"cpu_count": os.cpu_count(), "load_avg_1min_before": load_before,
              "load_avg_1min_after": os.getloadavg()[0], "repeats": repeats,
              "workers": workers, "trials": runs["cold"][0]["trials"]}
    for case, items in runs.items():
        for key in ("wall_s", "loocv_runtime_s", "first_progress_s"):
            values = [r[key] for r in items if r[key] is not None]
            result[f"evaluate_{case}_{key}"] = float(np.median(values)) if values else None
    result["warm_vs_cold_wall_ratio"] = (result["evaluate_warm_wall_s"]
                                         / result["evaluate_cold_wall_s"])
    return result


def main(argv=None) -> int:
    """Run ``python -m sandbox.bench.evaluate`` with ``argv``; return the exit status."""
    parser = argparse.ArgumentParser(prog="python -m sandbox.bench.evaluate",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", required=True, help="a folder or synthetic:NAME")
    parser.add_argument("--repeats", type=int, default=1, help="runs per case (median)")
    parser.add_argument("--workers", type=int, default=2, help="evaluate --workers (2)")
    parser.add_argument("--n-per-task", type=int, default=None,
                        help="trials per task (default all): a quicker run")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    if args.repeats < 1 or args.workers < 1:
        parser.error("--repeats and --workers: expected positive integers")
    print_result(run(args.data, args.repeats, args.workers, args.n_per_task), args.json, 36)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
