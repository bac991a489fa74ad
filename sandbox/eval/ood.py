"""Out-of-distribution honesty: does the familiarity fire on motions of a task never trained?

Leave each task out in turn (``python -m sandbox ood --data DIR``, whose report,
:mod:`sandbox.eval.oodreport`, adds detection at fixed false-alarm rates, AUC
and delays; ``python -m sandbox.eval.ood`` is its deprecated alias):

* **held-in** motions: every trial of the trained tasks, streamed causally
  (as the evaluation's test streams) and scored by a model fitted on the
  other trained trials (leave-one-out). Its familiarity is calibrated
  (:func:`~sandbox.core.familiarity.Calibration.from_records`) on the
  leave-one-out records of the *other* trained trials, so the trial never
  reaches its own calibration;
* **left-out** motions: every trial of the left-out task, scored by the model
  fitted on all trained trials and calibrated on all of their leave-one-out records.

A motion is *flagged* when an update's familiarity is below the calibration's
threshold. Three rules are reported: at any update of the whole recording
(the rule the threshold is calibrated for), at any update up to the motion's
true end (the handover; the recordings run on ~0.6 s after it), and at the
final update only. The false-alarm rate is the share of held-in motions
flagged, the detection rate the share of left-out ones; the trade-off is
swept over the calibration's ``alpha``.
"""

from __future__ import annotations

import sys
import time
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context

import numpy as np

from sandbox.core.conformal import conformal_threshold
from sandbox.core.familiarity import leave_one_out, stream_record
from sandbox.eval.loocv import EvalConfig, prepare
from sandbox.validation import check_choice

ALPHAS = (0.01, 0.02, 0.05, 0.1, 0.2)
RULES = ("any update", "any update to the handover", "final update")


def fold_jobs(train) -> list[tuple[str, int, tuple[int, ...]]]:
    """Every (left-out task, trial, training trials) to score.

    A held-in trial i is scored by the trained trials without i; a left-out
    trial by all trained trials.
    """
    tasks = sorted({d.task for d in train})
    jobs = []
    for left in tasks:
        inn = tuple(i for i, d in enumerate(train) if d.task != left)
        jobs += [(left, i, tuple(j for j in inn if j != i)) for i in inn]
        jobs += [(left, i, inn) for i, d in enumerate(train) if d.task == left]
    return jobs


_STATE: dict = {}


def _score(job) -> dict:
    """Familiarity statistics of one trial's stream under one training set."""
    left, i, fit_on = job
    train, test, fits, config, dow_t = (_STATE[k] for k in
                                        ("train", "test", "fits", "config", "dow_t"))
    model = config.model().fit_demo_fits([fits[j] for j in fit_on], train[fit_on[0]])
    d = test[i]
    t = d.times - d.times[0]
    end = float(t[model.motion_end(t, d.robot, train[i].human)])
    own = model.task_index(d.task) if d.task != left else None
    times, stats, tasks, ended, *under = stream_record(
        model, t, d.human, dow_t=dow_t, subsample=config.subsample,
        n_candidates=config.n_candidates, refine_steps=config.refine_steps, ended=True, own=own)
    return {"left_out": left, "trial": i, "task": d.task, "held_in": d.task != left,
            "source": d.source, "end": end, "times": times.tolist(), "stats": stats.tolist(),
            **({"own_stats": under[0].tolist()} if under else {}),
            "ended": ended.tolist(), "chosen": [model.tasks[k] for k in tasks],
            "tasks": list(model.tasks),
            "mean_duration": float(np.dot(model.priors,
                                          [m.mean_duration for m in model.task_models]))}


def score_all(train, test, config: EvalConfig, *, dow_t: float = 0.2, workers: int = 1,
              progress: bool = False) -> list[dict]:
    """The records (update times, statistics) of every job of :func:`fold_jobs`."""
    train, test, fits = prepare(train, test, config)
    _STATE.update(train=train, test=test, fits=fits, config=config, dow_t=dow_t)
    jobs = fold_jobs(train)
    out = []
    if workers <= 1:
        for n, job in enumerate(jobs):
            out.append(_score(job))
            _progress(progress, n + 1, len(jobs))
    else:
        with ProcessPoolExecutor(workers, mp_context=get_context("fork")) as pool:
            for n, res in enumerate(pool.map(_score, jobs, chunksize=4)):
                out.append(res)
                _progress(progress, n + 1, len(jobs))
    return out


def _progress(enabled: bool, n: int, total: int) -> None:
    if enabled and (n % 25 == 0 or n == total):
        print(f"  scored {n}/{total} streams", file=sys.stderr, flush=True)


def rank(records: list[dict], edges=None, score: str = "timing",
         gate: float | None = None, cells: str = "own") -> list[dict]:
    """Per record: its familiarity at each update and the reference it is thresholded with.

    Per left-out task, the held-in records are the calibration
    (:func:`~sandbox.core.familiarity.leave_one_out`): a held-in record is ranked
    against the others, and its reference is the others' lowest familiarities;
    a left-out record is ranked against all of them, its reference is all their
    lowest familiarities. ``edges`` are the time bins as fractions of the mean
    duration (default :data:`~sandbox.core.familiarity.EDGES`). ``score`` is what the
    calibration ranks (:data:`~sandbox.core.familiarity.SCORE_NAMES`, but not the
    Mahalanobis term alone): ``"timing"`` keeps the first four recorded statistics,
    ``"goal"`` those and the fifth, ``"position"`` those and the sixth, ``"all"`` six
    (records before the position have five). ``gate``: only the
    updates before the motion's estimated end are calibrated and ranked
    (:func:`~sandbox.core.conformal.ongoing` at that level of the records'
    ``ended``; the others' familiarity is NaN), None: all. ``cells``: the calibration's
    cells are filed from each held-in record's statistics under its own task
    (``"own"``, its ``own_stats``; :mod:`sandbox.core.cells`) or under the task chosen at
    each update (``"chosen"``, what records made before own-task cells allow).
    """
    from sandbox.core.familiarity import CELLS, EDGES, SCORE_NAMES, SCORES

    names = SCORE_NAMES[check_choice(score, "score", SCORES[:-1])]
    labelled = check_choice(cells, "cells", CELLS) == "own"
    if labelled and any(r["held_in"] and "own_stats" not in r for r in records):
        raise ValueError("records: expected each held-in motion's statistics under its own "
                         "task ('own_stats', records made since own-task cells) for "
                         "cells='own'; rank older records with cells='chosen'")
    stats = _picker(names, gate)
    fractions = np.asarray(EDGES if edges is None else edges, dtype=float)
    out = []
    for left in sorted({r["left_out"] for r in records}):
        pool = [r for r in records if r["left_out"] == left and r["held_in"]]
        tasks = pool[0]["tasks"]
        mean = float(np.mean([r["mean_duration"] for r in pool]))
        own = ([(r["times"], stats(r, "own_stats"), [tasks.index(r["task"])] * len(r["times"]))
                for r in pool] if labelled else None)
        full, held = leave_one_out(
            [(r["times"], stats(r), [tasks.index(k) for k in r["chosen"]]) for r in pool],
            len(tasks), edges=fractions * mean, own=own,
            components=names if np.ndim(pool[0]["stats"]) == 2 else ("mahalanobis",))
        lowest = np.array([h.min(initial=np.inf) for h in held])
        for i, r in enumerate(pool):
            fam = np.full(len(r["times"]), np.nan)
            v = stats(r)
            fam[np.isfinite(v[:, 0] if v.ndim == 2 else v)] = held[i]
            out.append({**r, "familiarity": fam.tolist(),
                        "reference": np.delete(lowest, i).tolist()})
        for r in records:
            if r["left_out"] == left and not r["held_in"]:
                fam = [full.familiarity(t, v, tasks.index(k))
                       for t, v, k in zip(r["times"], stats(r), r["chosen"])]
                out.append({**r, "familiarity": fam, "reference": lowest.tolist()})
    return out


def _picker(names: tuple, gate: float | None):
    """``stats(record, key)``: the statistics ``names`` of a record's updates (records keep
    all they have), NaN past the estimated end with a ``gate`` (:func:`rank`)."""
    from sandbox.core.conformal import ongoing
    from sandbox.core.familiarity import COMPONENTS

    keep = [COMPONENTS.index(n) for n in names]

    def stats(r, key="stats"):
        v = np.array(r[key], dtype=float)
        if v.ndim == 2 and v.shape[1] <= max(keep):
            raise ValueError(f"records: expected the statistics {names}, got {v.shape[1]} "
                             f"per update (records made before the position have five)")
        v = v[:, keep] if v.ndim == 2 else v
        if gate is not None:
            v[~ongoing(r["ended"], gate)] = np.nan
        return v

    return stats


def judge(ranked: list[dict], alpha: float = 0.05) -> list[dict]:
    """Flag each ranked record (:func:`rank`) by each rule at calibration level ``alpha``."""
    out = []
    for r in ranked:
        threshold = conformal_threshold(r["reference"], alpha)
        low = np.asarray(r["familiarity"]) < threshold
        before = np.asarray(r["times"]) <= r["end"] + 1e-9
        out.append({**r, "threshold": threshold,
                    "flags": {RULES[0]: bool(low.any()), RULES[1]: bool(low[before].any()),
                              RULES[2]: bool(low[-1]) if low.size else False}})
    return out


def rates(judged: list[dict]) -> dict:
    """False-alarm and detection rates per rule, overall and per left-out task."""
    out = {}
    for rule in RULES:
        row = {}
        for left in sorted({r["left_out"] for r in judged}) + [None]:
            sel = [r for r in judged if left is None or r["left_out"] == left]
            held = [r["flags"][rule] for r in sel if r["held_in"]]
            new = [r["flags"][rule] for r in sel if not r["held_in"]]
            row[left or "all"] = {"false_alarm": float(np.mean(held)),
                                  "detection": float(np.mean(new)),
                                  "n_held_in": len(held), "n_left_out": len(new)}
        out[rule] = row
    return out


def tradeoff(ranked: list[dict], alphas=ALPHAS) -> list[dict]:
    """False alarms and detections (all left-out tasks) for each calibration ``alpha``."""
    rows = []
    for a in alphas:
        r = rates(judge(ranked, a))
        rows.append({"alpha": a, **{rule: r[rule]["all"] for rule in RULES}})
    return rows


def markdown(result: dict) -> str:
    """The README tables of one evaluation (:func:`run`)."""
    lines = [f"Leave-task-out on `{result['data']}` (observe {result['observe']}; "
             f"dow_t = {result['dow_t']:g} s, calibration alpha = {result['alpha']:g}); "
             f"{result['n_streams']} streams, {result['seconds']:.0f} s.", "",
             "| left-out task | rule | false alarms (held-in) | detection (left-out) |",
             "|---|---|---|---|"]
    for rule, row in result["rates"].items():
        for left, v in row.items():
            lines.append(f"| {left} | {rule} | {v['false_alarm']:.3f} ({v['n_held_in']}) | "
                         f"{v['detection']:.3f} ({v['n_left_out']}) |")
    lines += ["", "| alpha | " + " | ".join(f"FA / detection, {r}" for r in RULES) + " |",
              "|---|" + "---|" * len(RULES)]
    for row in result["tradeoff"]:
        cells = [f"{row[r]['false_alarm']:.3f} / {row[r]['detection']:.3f}" for r in RULES]
        lines.append(f"| {row['alpha']:g} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def run(data: str, *, observe=None, dow_t: float = 0.2, alpha: float = 0.05,
        workers: int = 1, progress: bool = False) -> dict:
    """Leave each task out in turn on ``data``; returns records, rates and the trade-off."""
    from sandbox.eval.datasets import load_pair

    config = EvalConfig(observe=None if observe is None else tuple(observe))
    start = time.perf_counter()
    train, test, _ = load_pair(data, observe=observe)
    if len({d.task for d in train}) < 3:
        raise ValueError(f"data: expected at least three tasks (two stay trained), got "
                         f"{sorted({d.task for d in train})}")
    records = score_all(train, test, config, dow_t=dow_t, workers=workers, progress=progress)
    return summarize(records, data=str(data), observe=",".join(observe or ["hand"]),
                     dow_t=dow_t, alpha=alpha, seconds=time.perf_counter() - start)


def summarize(records: list[dict], *, alpha: float = 0.05, **about) -> dict:
    """Rates at ``alpha`` and the trade-off of scored records (:func:`score_all`)."""
    ranked = rank(records)
    return {**about, "alpha": alpha, "n_streams": len(records),
            "rates": rates(judge(ranked, alpha)), "tradeoff": tradeoff(ranked),
            "records": ranked}


def main(argv=None) -> int:
    """``python -m sandbox.eval.ood``: a deprecated alias of ``python -m sandbox ood``.

    Kept for one release: its options (``--data``, ``--observe``, ``--dow-t``,
    ``--alpha``, ``--workers``, ``--out``, ``--records``) mean the same there;
    this runs the command in a child process (the evaluation layer does not
    import the commands) and returns its exit status.
    """
    import subprocess

    print("note: 'python -m sandbox.eval.ood' is deprecated and goes in the next release; "
          "use 'python -m sandbox ood' (same options)", file=sys.stderr, flush=True)
    args = sys.argv[1:] if argv is None else list(argv)
    return subprocess.call([sys.executable, "-m", "sandbox", "ood", *args])


if __name__ == "__main__":
    raise SystemExit(main())
