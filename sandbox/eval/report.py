"""Aggregate per-trial results into ``report.json`` (the keys of the evaluation issue).

Every section holds, per task and for the task ``"mean"`` (macro-average: the
mean of the task means, as the paper averages over tasks), the mean of each
measure and its 95 % bootstrap confidence interval (``<measure>_ci``,
resampling trials within tasks). Beyond the paper: calibration (``nll`` per
step, ``coverage`` of the 95 % ellipsoid), command jumps at updates, recognition
over time (``recognition_over_time``: the fraction of trials whose task is
believed at each fraction of the recording; ``recognition_over_time_ci``: its
bootstrap intervals and its late decay, peak minus end), the differences
static - dynamic for every ratio and window.

Recognition comes in two figures, named apart everywhere: **task-averaged**
(``recognition``: the mean over tasks of each task's rate, as the paper's
tables) and **share of trials** (``recognition_share`` beside it in each
section's ``"mean"``, and the curve ``recognition_over_time``). They differ when
the tasks have unequal numbers of trials; ``recognition_over_time_task_averaged``
is the curve averaged the other way.
"""

from __future__ import annotations

from itertools import permutations

import numpy as np

from sandbox.eval import metrics

GAMMAS = [(1 / 3, 1 / 3, 1 / 3)] + sorted(set(permutations((0.5, 0.25, 0.25))), reverse=True)
MEASURES = ("e_p", "e_q", "e_phi")


def gamma_label(gamma) -> str:
    """"0.33,0.33,0.33" style label of a weight triple."""
    return ",".join(f"{g:.2f}" for g in gamma)


def _section(trials: list[dict], tasks: list[str], get, keys, n_boot: int,
             draws_cache: dict | None = None) -> dict:
    """Per task and over tasks ("mean"): each measure's mean and bootstrap interval.

    Every measure of one row set is resampled with the same draws (a fresh
    ``default_rng(0)`` per set, as each measure had before); ``draws_cache``
    keeps them across sections that share the row set.
    """
    cache = {} if draws_cache is None else draws_cache
    labels = np.array([r["task"] for r in trials])
    out: dict = {}
    for task in tasks + ["mean"]:
        rows = trials if task == "mean" else [r for r, lab in zip(trials, labels) if lab == task]
        groups = np.array([r["task"] for r in rows])
        key_ = (task, groups.tobytes(), n_boot)
        if key_ not in cache:
            cache[key_] = metrics.within_group_draws(groups, n_boot, np.random.default_rng(0))
        entry: dict = {}
        for key in keys:
            raw = [get(r)[key] for r in rows]
            if raw and all(v is None for v in raw):     # not applicable (e_q in task space)
                entry[key], entry[f"{key}_ci"] = None, [None, None]
                continue
            values = np.array(raw, dtype=float)
            if task == "mean":
                entry[key] = float(np.mean([values[groups == g].mean() for g in tasks]))
            else:
                entry[key] = float(values.mean())
            if values.size:
                lo, hi = metrics.bootstrap_ci(values, groups, draws=cache[key_])
            else:
                lo, hi = float("nan"), float("nan")
            entry[f"{key}_ci"] = [lo, hi]
            if task == "mean" and key == "recognition" and values.size:
                entry["recognition_share"] = float(values.mean())     # of trials, not tasks
                entry["recognition_share_ci"] = list(metrics.bootstrap_ci(
                    values, groups, draws=cache[key_], statistic="pooled"))
        out[task] = entry
    return out


def build_report(trials: list[dict], config: dict, dataset: str, runtime_s: float,
                 n_boot: int = 1000) -> dict:
    """The report dictionary (see the module docstring)."""
    tasks = list(dict.fromkeys(r["task"] for r in trials))
    draws: dict = {}
    ratios = [f"{f:.1f}" for f in config["ratios"]]
    windows = [f"{w:.1f}" for w in config["windows"]]
    report = {
        "dataset": dataset,
        "tasks": tasks,
        "n_trials": {t: sum(r["task"] == t for r in trials) for t in tasks},
        "config": config,
        "static": {f: _section(trials, tasks, lambda r, f=f: r["static"][f],
                               MEASURES + ("recognition", "nll", "coverage"), n_boot, draws)
                   for f in ratios},
        "dynamic": {w: _section(trials, tasks, lambda r, w=w: r["dynamic"][w],
                                MEASURES + ("recognition", "time_to_correct", "nll",
                                            "coverage"), n_boot, draws)
                    for w in windows},
        "oracle": _section(trials, tasks, lambda r: r["oracle"], MEASURES + ("nll", "coverage"),
                           n_boot, draws),
    }
    report["window_metric"], report["best_window"] = _window_metric(report, windows)
    report["differences"] = {                                   # eq. 19: static - dynamic
        f: {w: {m: _minus(report["static"][f]["mean"][m], report["dynamic"][w]["mean"][m])
                for m in MEASURES} for w in windows} for f in ratios}
    report["static_recognition"] = {
        task: {f: report["static"][f][task]["recognition"] for f in ratios}
        for task in tasks + ["mean"]}
    report["recognition_over_time"] = {
        "fractions": list(config["curve"]),
        **{w: np.mean([r["dynamic"][w]["recognition_curve"] for r in trials], axis=0).tolist()
           for w in windows}}
    labels = [r["task"] for r in trials]
    report["recognition_over_time_task_averaged"] = {
        "fractions": list(config["curve"]),
        **{w: np.mean([np.mean([r["dynamic"][w]["recognition_curve"] for r in trials
                                if r["task"] == t], axis=0) for t in tasks], axis=0).tolist()
           for w in windows}}
    report["recognition_over_time_ci"] = {
        w: metrics.curve_bootstrap([r["dynamic"][w]["recognition_curve"] for r in trials],
                                   labels, n_boot=n_boot) for w in windows}
    report["jumps"] = {w: _jumps([j for r in trials for j in r["dynamic"][w]["jumps"]])
                       for w in windows}
    report["runtime_s"] = round(float(runtime_s), 2)
    return report


def _minus(a, b):
    """``a - b``, None when a measure does not apply (e_q of a task-space robot part)."""
    return None if a is None or b is None else a - b


def fmt(value, spec: str = ".3f") -> str:
    """A measure in a table: ``format(value, spec)``, "n/a" for None (not applicable)."""
    return "n/a" if value is None else format(value, spec)


def _window_metric(report: dict, windows: list[str]):
    errors = {m: [report["dynamic"][w]["mean"][m] for w in windows] for m in MEASURES}
    metric, best = {}, {}
    for gamma in GAMMAS:
        values = metrics.window_metric(errors, gamma)
        label = gamma_label(gamma)
        metric[label] = dict(zip(windows, values))
        best[label] = windows[int(np.argmin(values))]
    return metric, best


def _jumps(values: list[float]) -> dict:
    v = np.asarray(values, dtype=float)
    if v.size == 0:
        return {"n": 0}
    return {"n": int(v.size), "mean": float(v.mean()), "median": float(np.median(v)),
            "p95": float(np.quantile(v, 0.95)), "max": float(v.max())}


def to_markdown(report: dict) -> str:
    """Tables of a report in Markdown (means with 95 % bootstrap intervals)."""
    lines = [f"### Evaluation of `{report['dataset']}`", "",
             f"{sum(report['n_trials'].values())} trials "
             f"({', '.join(f'{t}: {n}' for t, n in report['n_trials'].items())}), "
             f"{_mode(report['config'])}, {report['runtime_s']} s.", ""]
    share = ("recognition_share",) if "recognition_share" in next(
        iter(report["dynamic"].values()))["mean"] else ()
    lines += _table("Dynamic formulation (mean over tasks)",
                    {f"dow_t = {w} s": report["dynamic"][w]["mean"] for w in report["dynamic"]},
                    MEASURES + ("recognition",) + share + ("time_to_correct", "coverage"))
    lines += _table("Static formulation (mean over tasks)",
                    {f"ratio {f}": report["static"][f]["mean"] for f in report["static"]},
                    MEASURES + ("recognition",) + share + ("coverage",))
    lines += _table("Oracle (all observations, true task and duration)",
                    {"oracle": report["oracle"]["mean"]}, MEASURES)
    lines += ["#### Static recognition rate by task and ratio (paper Table II)", "",
              "| ratio | " + " | ".join(report["tasks"]) + " | mean |",
              "|---|" + "---|" * (len(report["tasks"]) + 1)]
    for f in report["static"]:
        cells = [f"{report['static_recognition'][t][f]:.2f}" for t in report["tasks"] + ["mean"]]
        lines.append(f"| {f} | " + " | ".join(cells) + " |")
    lines += ["", "#### Window-selection metric m (lower is better)", "",
              "| gamma (e_p, e_q, e_phi) | " + " | ".join(report["dynamic"]) + " | best |",
              "|---|" + "---|" * (len(report["dynamic"]) + 1)]
    for label, values in report["window_metric"].items():
        cells = [f"{values[w]:.3f}" for w in report["dynamic"]]
        lines.append(f"| {label} | " + " | ".join(cells) + f" | {report['best_window'][label]} |")
    if "per_session" in report:
        lines += [""] + _sessions_table(report)
    return "\n".join(lines) + "\n"


def _mode(config: dict) -> str:
    """How the trials were predicted: leave-one-out, test-only by a given model,
    cross-session or leave-one-session-out."""
    mode = config.get("mode")
    if mode == "test-only":
        return f"test-only: all predicted by the model `{config.get('model')}` (no refit)"
    if mode == "cross-session":
        return (f"cross-session: all predicted by a model fitted on `{config.get('train')}` "
                f"({config.get('n_train')} trials)")
    if mode == "leave-one-session-out":
        return (f"leave-one-session-out over {len(config.get('sessions', []))} sessions "
                f"({', '.join(config.get('sessions', []))})")
    return "leave-one-out"


def _sessions_table(report: dict) -> list[str]:
    """Each session's means (``per_session``) at the dynamic windows and static ratios."""
    keys = ("e_p", "e_q", "e_phi", "recognition")
    out = ["#### By session (mean over the session's tasks)", "",
           "| session | trials | formulation | " + " | ".join(keys) + " |",
           "|---|---|---|" + "---|" * len(keys)]
    for name, entry in report["per_session"].items():
        n = sum(entry["n_trials"].values())
        rows = [(f"dow_t = {w} s", v) for w, v in entry["dynamic"].items()]
        rows += [(f"ratio {f}", v) for f, v in entry["static"].items()]
        for label, values in rows:
            out.append(f"| {name} | {n} | {label} | "
                       + " | ".join(fmt(values[k]) for k in keys) + " |")
    return out + [""]


#: Column names of measures whose key alone would be ambiguous.
NAMES = {"recognition": "recognition (task-averaged)",
         "recognition_share": "recognition (share of trials)"}


def _table(title: str, rows: dict, keys) -> list[str]:
    units = {"e_p": "m", "e_q": "rad", "e_phi": "s"}
    head = " | ".join(f"{k} ({units[k]})" if k in units else NAMES.get(k, k) for k in keys)
    out = [f"#### {title}", "", f"| | {head} |", "|---|" + "---|" * len(keys)]
    for name, entry in rows.items():
        cells = [fmt(entry[k]) if entry[k] is None else
                 f"{entry[k]:.3f} [{entry[k + '_ci'][0]:.3f}, {entry[k + '_ci'][1]:.3f}]"
                 for k in keys]
        out.append(f"| {name} | " + " | ".join(cells) + " |")
    return out + [""]
