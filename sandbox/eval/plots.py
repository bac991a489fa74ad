"""The paper's evaluation figures from ``report.json`` files (the only matplotlib user).

Figures are drawn with matplotlib's object API (no pyplot), so plotting from a
notebook leaves its inline backend alone.

* ``direct.png``: e_p, e_q, e_phi against dow_t, per task and mean (paper Fig. 5).
* ``comparative.png``: static - dynamic differences against the observed ratio,
  one curve per window (paper Fig. 6).
* ``average_comparison.png`` (two reports): the differences averaged over
  windows, one curve per report (Exp. 1 vs Exp. 2, paper Fig. 8).
* ``recognition.png``: recognition over the motion (dynamic, per window) and
  against the observed ratio (static).
* :func:`plot_curves` (``modalities.png``): recognition over the recording for
  several reports (e.g. observation sets), with bootstrap bands.
* :func:`plot_methods` (``recognition.png`` of ``compare``): recognition over the
  recording of several methods, with bootstrap bands.
* :func:`plot_sweep` (``summary.png``): the objective J of every configuration
  of a sweep, best first.
* :func:`plot_roc` (``ood --plot``): detection before the handover against false
  alarms on held-out normal motions, one curve per OOD set or left-out task.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

UNITS = {"e_p": "m", "e_q": "rad", "e_phi": "s"}
MEASURES = (("e_p", "goal position error e_p (m)"), ("e_q", "joint RMS error e_q (rad)"),
            ("e_phi", "phase error e_phi (s)"))


def _figure(ncols: int, size):
    """A figure and its axes without pyplot, so no global backend is touched."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=size)
    return fig, fig.subplots(1, ncols)


def plot_report(report: dict, out_dir, other: dict | None = None) -> list[Path]:
    """Write the figures of one report (and the comparison with ``other``); returns paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = [_direct(report, out / "direct.png"), _comparative(report, out / "comparative.png"),
             _recognition(report, out / "recognition.png")]
    if other is not None:
        paths.append(_average(report, other, out / "average_comparison.png"))
    return paths


def _windows(report):
    return list(report["dynamic"])


def _direct(report, path):
    fig, axes = _figure(3, (13, 3.8))
    windows = _windows(report)
    x = [float(w) for w in windows]
    for ax, (key, label) in zip(axes, MEASURES):
        if report["dynamic"][windows[0]]["mean"][key] is None:     # e_q in task space
            ax.text(0.5, 0.5, f"{key}: n/a\n(robot part in task space)", ha="center",
                    transform=ax.transAxes)
            ax.set_axis_off()
            continue
        for task in report["tasks"] + ["mean"]:
            y = np.array([report["dynamic"][w][task][key] for w in windows], dtype=float)
            style = dict(color="k", lw=2.5) if task == "mean" else dict(lw=1.2, alpha=0.8)
            ax.plot(x, y, marker="o", label=task, **style)
        ci = np.array([report["dynamic"][w]["mean"][key + "_ci"] for w in windows],
                      dtype=float)                    # None (e_q in task space): not drawn
        ax.fill_between(x, ci[:, 0], ci[:, 1], color="k", alpha=0.12)
        ax.set_xscale("log")
        ax.set_xticks(x, [f"{v:g}" for v in x])
        ax.set_xlabel("dynamic window dow_t (s)")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle(f"Direct evaluation of the dynamic formulation: {report['dataset']}")
    return _save(fig, path)


def _comparative(report, path):
    fig, axes = _figure(3, (13, 3.8))
    ratios = list(report["static"])
    x = [float(f) for f in ratios]
    for ax, (key, label) in zip(axes, MEASURES):
        for w in _windows(report):
            y = np.array([report["differences"][f][w][key] for f in ratios], dtype=float)
            ax.plot(x, y, marker="o", label=f"dow_t = {w} s")
        ax.axhline(0.0, color="k", lw=0.8)
        ax.set_xlabel("static observed ratio f")
        ax.set_ylabel(f"static - dynamic {key} ({UNITS[key]})")
        ax.set_title(label, fontsize=9)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle("Comparative evaluation (positive: the dynamic formulation is better)")
    return _save(fig, path)


def _average(report, other, path):
    fig, axes = _figure(3, (13, 3.8))
    for rep in (report, other):
        ratios = list(rep["static"])
        x = [float(f) for f in ratios]
        for ax, (key, label) in zip(axes, MEASURES):
            y = [np.array([rep["differences"][f][w][key] for w in _windows(rep)],
                          dtype=float).mean() for f in ratios]
            ax.plot(x, y, marker="o", label=rep["dataset"])
            ax.axhline(0.0, color="k", lw=0.8)
            ax.set_xlabel("static observed ratio f")
            ax.set_ylabel(f"static - dynamic {key} ({UNITS[key]})")
            ax.set_title(f"mean over windows: {label}", fontsize=9)
            ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle("Average comparison of two experiments")
    return _save(fig, path)


def _recognition(report, path):
    fig, axes = _figure(2, (11, 3.8))
    curve = report["recognition_over_time"]
    for w in _windows(report):
        axes[0].plot(curve["fractions"], curve[w], marker="o", label=f"dynamic, dow_t = {w} s")
    axes[0].set_xlabel("fraction of the recording observed (idle tail included)")
    axes[0].set_ylabel("share of trials with the right task")
    axes[0].set_ylim(0, 1.02)
    axes[0].axhline(1 / len(report["tasks"]), color="k", ls=":", label="chance")
    axes[0].legend(fontsize=8)
    ratios = list(report["static"])
    for task in report["tasks"] + ["mean"]:
        y = [report["static_recognition"][task][f] for f in ratios]
        style = dict(color="k", lw=2.5) if task == "mean" else dict(lw=1.2)
        axes[1].plot([float(f) for f in ratios], y, marker="o", label=task, **style)
    axes[1].set_xlabel("static observed ratio f")
    axes[1].set_ylabel("static recognition rate (task-averaged: mean)")
    axes[1].set_ylim(0, 1.02)
    axes[1].legend(fontsize=8)
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.suptitle(f"Task recognition: {report['dataset']}")
    return _save(fig, path)


def plot_curves(reports: dict[str, dict], path, window: str = "0.2",
                title: str = "Recognition over the recording") -> Path:
    """Recognition over the recording of several reports, one curve (and its 95 %
    bootstrap band) per label; the chance level of the first report's tasks."""
    fig, axes = _figure(1, (7, 4))
    ax = axes
    first = None
    for label, report in reports.items():
        first = first or report
        band = report["recognition_over_time_ci"][window]
        x = report["recognition_over_time"]["fractions"]
        line = ax.plot(x, band["mean"], marker="o", label=label)[0]
        ax.fill_between(x, band["lo"], band["hi"], color=line.get_color(), alpha=0.12)
    ax.axhline(1 / len(first["tasks"]), color="k", ls=":", label="chance")
    ax.set_xlabel("fraction of the recording observed (idle tail included)")
    ax.set_ylabel(f"share of trials with the right task (dow_t = {window} s)")
    ax.set_ylim(0, 1.02)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    fig.suptitle(title)
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    return _save(fig, Path(path))


def plot_methods(comparison: dict, path) -> Path:
    """Recognition over the recording of every method of a comparison
    (:mod:`sandbox.eval.compare`), one curve and its 95 % bootstrap band each."""
    fig, ax = _figure(1, (7, 4))
    x = comparison["curve"]
    for method, row in comparison["rows"].items():
        line = ax.plot(x, row["recognition_curve"], marker="o", label=method)[0]
        lo, hi = row["recognition_curve_ci"]
        ax.fill_between(x, lo, hi, color=line.get_color(), alpha=0.10)
    ax.axhline(1 / max(1, len(comparison["tasks"])), color="k", ls=":", label="chance")
    ax.set_xlabel("fraction of the recording observed (idle tail included)")
    ax.set_ylabel("trials with the right task")
    ax.set_ylim(0, 1.02)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    observed = comparison["config"]["evaluation"].get("observe") or ["all"]
    fig.suptitle(f"Recognition over the recording: {comparison['n_trials']} trials, "
                 f"{comparison['split']}, observing {','.join(observed)}", fontsize=10)
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    return _save(fig, Path(path))


def plot_sweep(summary: dict, path) -> Path:
    """The objective J of each configuration of a sweep's summary, one bar each, best on top."""
    ranked = summary["ranked"]
    fig, ax = _figure(1, (8, 1.5 + 0.3 * max(1, len(ranked))))
    y = np.arange(len(ranked))[::-1]
    ax.barh(y, [e["J"] for e in ranked], color="tab:blue")
    ax.set_yticks(y, [f"{e['rank']}. {e['label']}" for e in ranked], fontsize=8)
    ax.set_xlabel("objective J (lower is better)")
    ax.grid(axis="x", alpha=0.3)
    failed = len(summary["failed"])
    fig.suptitle(f"Sweep: {len(ranked)} configurations ranked"
                 + (f", {failed} failed" if failed else ""))
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    return _save(fig, Path(path))


def plot_roc(result: dict, path) -> Path:
    """ROC curves of an ``ood`` result (:mod:`sandbox.eval.oodreport`), one per group."""
    from sandbox.eval.oodreport import FA_RATES, groups, roc

    fig, ax = _figure(1, (5.5, 5))
    auc = {g: v["auc"] for g, v in result["groups"].items()}
    for g, (normal, ood) in groups(result["records"]).items():
        fa, det = roc(normal, ood)
        ax.step(fa, det, where="post", lw=2.5 if g == "all" else 1.3,
                color="k" if g == "all" else None, label=f"{g} (AUC {auc[g]:.2f})")
    for rate in FA_RATES:
        ax.axvline(rate, color="0.7", lw=0.8, ls=":")
    ax.plot([0, 1], [0, 1], color="0.6", lw=0.8, ls="--")
    ax.set_xlabel("false alarms (held-out normal motions)")
    ax.set_ylabel("detection before the handover")
    ax.set_xlim(0, 1), ax.set_ylim(0, 1.02)
    ax.legend(fontsize=7, loc="lower right")
    ax.set_title(f"{result['mode']}: {Path(str(result['data'])).name} ({result['observe']})",
                 fontsize=9)
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    return _save(fig, Path(path))


def _save(fig, path: Path) -> Path:
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    return path
