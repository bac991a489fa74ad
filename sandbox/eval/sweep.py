"""Leave-one-out of every configuration of a grid, on local processes or a Dask cluster.

:func:`sweep` is ``python -m sandbox sweep``: it reads a grid
(:mod:`sandbox.eval.grid`), loads the trials once, and evaluates every
configuration on every leave-one-out fold. The work is split into tasks of one
configuration and a chunk of its folds
(:func:`~sandbox.eval.evaluation.chunk_folds`), run by an executor
(:mod:`sandbox.eval.executors`) through an
:class:`~sandbox.eval.evaluation.Evaluation`. A configuration's results do not
depend on the executor, the number of workers or the chunks.

The output folder holds:

* ``sweep.json``: what was swept (the grid's points, the base configuration,
  the data options); a folder holding another sweep is refused unless ``force``;
* ``results/<key>.json``: one file per configuration, written atomically when
  it finishes, with its options, report and objective. The key hashes the full
  configuration, the trials themselves and the package version, so a re-run
  skips what is done and never reuses a result of other options or data;
* ``summary.json``, ``summary.md``, ``summary.png``: the configurations ranked
  by tuning's objective J (:func:`~sandbox.eval.tune.objective`, lower is
  better), and the ones that failed.
"""

from __future__ import annotations

import hashlib
import json
import sys
from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from pathlib import Path

import sandbox
from sandbox.eval.evaluation import Evaluation, canonical, config_key, write_atomic
from sandbox.eval.executors import open_executor
from sandbox.eval.grid import config_for, label
from sandbox.eval.loocv import EvalConfig
from sandbox.eval.tune import config_row

MANIFEST = "sweep.json"


def _stderr(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


# ---------------------------------------------------------------- the output folder
def manifest(points: list[dict], base: EvalConfig, data: dict) -> dict:
    """What a sweep is (``sweep.json``): the points, the base configuration, the data options."""
    body = {"points": json.loads(canonical(points)), "base": json.loads(canonical(
        base.to_dict())), "data": json.loads(canonical(data))}
    body["fingerprint"] = hashlib.sha256(canonical(body).encode()).hexdigest()[:32]
    return body


def claim_out(out: str | Path, content: dict, *, force: bool = False,
              write: bool = True) -> Path:
    """Check that ``out`` is empty or holds this sweep (unless ``force``); mark it so
    (``sweep.json``) if ``write``.

    Raises
    ------
    ValueError
        ``out`` is a file, or holds another sweep's results or other files.
    """
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise ValueError(f"--out: expected a folder, got the file {str(out)!r}")
    path = out / MANIFEST
    if not force and out.is_dir() and any(out.iterdir()):
        try:
            held = json.loads(path.read_text()).get("fingerprint")
        except (OSError, ValueError, AttributeError):
            held = None
        if held != content["fingerprint"]:
            what = "another sweep's results" if held else "files that are not a sweep's"
            raise ValueError(f"--out {str(out)!r}: expected an empty folder or one of an "
                             f"earlier run of this sweep (same grid and data), got {what}; "
                             f"use --force to write there anyway")
    if write:
        write_atomic(path, json.dumps(content, indent=1))
    return out


def _result_path(out: Path, key: str) -> Path:
    return out / "results" / f"{key}.json"


def load_result(out: str | Path, key: str) -> dict | None:
    """The stored result of configuration ``key`` (None if absent or unreadable)."""
    try:
        result = json.loads(_result_path(Path(out), key).read_text())
    except (OSError, ValueError):
        return None
    return result if isinstance(result, dict) and result.get("key") == key else None


def stored_results(out: str | Path) -> dict[str, dict]:
    """Every result a sweep stored in ``out``, by file name, without its timings.

    Two sweeps of the same grid and data agree on this whatever their executor.
    """
    found = {}
    for path in sorted((Path(out) / "results").glob("*.json")):
        result = json.loads(path.read_text())
        result["report"].pop("runtime_s")
        result["row"].pop("runtime_s")
        found[path.name] = result
    return found


def run_sweep(executor, trials: Mapping, points: list[dict], out: str | Path, *,
              base: EvalConfig | None = None, data: dict | None = None, dataset: str = "",
              force: bool = False, chunk_size: int | None = None,
              log: Callable[[str], None] = _stderr) -> dict:
    """Evaluate every point of a grid; write results and summary to ``out``.

    Parameters
    ----------
    executor : ProcessExecutor or DaskExecutor
        From :func:`~sandbox.eval.executors.open_executor`.
    trials : mapping
        ``trials[observe]`` is the pair ``(train, test)`` of trials loaded with
        the modalities ``observe`` (a tuple, as in :class:`EvalConfig`) that some
        point observes (:func:`~sandbox.eval.datasets.load_pair`).
    points : list of dict
        From :func:`~sandbox.eval.grid.read_grid`.
    out : str or Path
        The output folder (see the module docstring).
    base : EvalConfig, optional
        The options the points do not set.
    data : dict, optional
        How the trials were obtained, for ``sweep.json`` (default: their hashes).
    dataset : str
        Label of the data in the reports.
    force : bool
        Write into a folder holding another sweep.
    chunk_size : int, optional
        Folds per task (default: see :func:`~sandbox.eval.evaluation.chunk_folds`).
    log : callable
        Receives one line per finished configuration.

    Returns
    -------
    dict
        The summary (``summary.json``).
    """
    from sandbox.eval.sweep_summary import write_summary

    base = base or EvalConfig()
    configs = [config_for(p, base) for p in points]
    missing = sorted({str(c.observe) for c in configs if c.observe not in trials})
    if missing:
        raise ValueError(f"trials: expected trials for every observe of the grid, "
                         f"missing {missing}")
    evaluation = Evaluation(executor, dataset=dataset, chunk_size=chunk_size)
    tokens = {obs: evaluation.add(*trials[obs]) for obs in dict.fromkeys(c.observe
                                                                         for c in configs)}
    out = claim_out(out, manifest(points, base, data or {"trials": sorted(tokens.values())}),
                    force=force)
    jobs = [(c, tokens[c.observe]) for c in configs]
    keys = [config_key(c, t) for c, t in jobs]
    results = {k: r for k in keys if (r := load_result(out, k)) is not None}
    todo = [job for job, k in zip(jobs, keys) if k not in results]
    if results:
        log(f"{len(results)} of {len(set(keys))} configurations already done in {out}")
    failed = _evaluate(evaluation, todo, points, keys, results, out, log)
    return write_summary(out, points, keys, results, failed, data or {})


def _evaluate(evaluation: Evaluation, todo: list, points: list[dict], keys: list[str],
              results: dict, out: Path, log: Callable[[str], None]) -> dict:
    """Run the jobs ``todo``; store each result in ``results`` and in ``out`` as it ends.
    Returns the failed configurations' errors by key."""
    failed: dict = {}
    for n, done in enumerate(evaluation.run(todo), 1):
        point = points[keys.index(done.key)]
        if done.report is None:
            failed[done.key] = done.error
            log(f"[{n}/{len(todo)}] failed: {label(point)}: {done.error}")
            continue
        results[done.key] = _result(done.key, point, done.config, done.report)
        write_atomic(_result_path(out, done.key), json.dumps(results[done.key], indent=1))
        log(f"[{n}/{len(todo)}] {label(point)}: J = {results[done.key]['row']['J']:.3f} "
            f"({done.report['runtime_s']:.1f} s of work)")
    return failed


def _result(key: str, point: dict, config: EvalConfig, report: dict) -> dict:
    return {"key": key, "point": json.loads(canonical(point)), "config": config.to_dict(),
            "version": sandbox.__version__,
            "row": config_row(report, config, config.windows[0], config.ratios[0]),
            "report": report}


def sweep(data: str, grid: str | Path, out: str | Path, *, workers: int = 2,
          scheduler: str | None = None, timeout: float | None = None, force: bool = False,
          seed: int = 0, tasks: Sequence[str] | None = None, n_per_task: int | None = None,
          spec=None, observe: Sequence[str] | None = None,
          log: Callable[[str], None] = _stderr, base: EvalConfig | None = None,
          cache=None) -> dict:
    """``python -m sandbox sweep``: check everything, load the trials, run the grid.

    The grid, ``workers``, the output folder and the scheduler are checked (a
    ``ValueError`` saying what was expected) before any trial is loaded.
    ``data``, ``seed``, ``tasks``, ``n_per_task`` and ``spec`` are those of
    :func:`~sandbox.eval.datasets.load_pair`; ``observe`` the modalities of the
    points that do not set ``observe`` (default the spec's). The trials are
    loaded once per distinct ``observe`` (the trials kept can depend on it).
    ``base``: the options of the points before their own values (default
    :class:`EvalConfig`'s; ``python -m sandbox sweep --config FILE``). ``cache``:
    keep loaded trials on disk (:func:`~sandbox.eval.datasets.load_pair`).
    Returns the summary.
    """
    from sandbox.data.spec import resolve
    from sandbox.eval.datasets import load_pair
    from sandbox.eval.executors import TIMEOUT
    from sandbox.eval.grid import read_grid

    points = read_grid(grid)
    if observe is None:
        observe = [m.name for m in resolve(spec).observed(None)]
    base = replace(base or EvalConfig(), observe=tuple(observe))
    configs = [config_for(p, base) for p in points]
    described = {"data": _where(data), "seed": seed, "tasks": list(tasks) if tasks else None,
                 "n_per_task": n_per_task, "spec": _where(spec) if spec else None}
    claim_out(out, manifest(points, base, described), force=force, write=False)
    with open_executor(workers, scheduler, TIMEOUT if timeout is None else timeout) as ex:
        trials = {}
        for obs in dict.fromkeys(c.observe for c in configs):
            train, test, skipped = load_pair(data, seed=seed, tasks=tasks,
                                             n_per_task=n_per_task, spec=spec, observe=obs,
                                             cache=cache)
            for reason in skipped:
                log(f"skipped ({','.join(obs)}): {reason}")
            if not train:
                from sandbox.data.skipped import no_usable

                raise no_usable(str(data), skipped)
            trials[obs] = (train, test)
        return run_sweep(ex, trials, points, out, base=base, data=described,
                         dataset=str(data), force=force, log=log)


def _where(value) -> str:
    """A data folder or spec file as an absolute path (other values as their text)."""
    if isinstance(value, str | Path):
        try:
            return str(Path(value).resolve(strict=True))
        except OSError:
            pass
    return str(value)
