"""The summary of a sweep: configurations ranked by tuning's objective J.

``summary.json`` (:func:`summarise`), ``summary.md`` (:func:`to_markdown`) and
``summary.png`` (:func:`~sandbox.eval.plots.plot_sweep`), written by
:func:`write_summary` into the sweep's folder.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

from sandbox.eval.grid import label

OBJECTIVE = ("J = e_p / 0.05 m + e_phi / 0.20 s + (1 - recognition) / 0.30 "
             "+ max(0, jump_p95 - 0.01 rad) / 0.01 rad (sandbox.eval.tune.objective); "
             "lower is better")
#: Columns of the Markdown table: (row key, heading).
COLUMNS = (("J", "J"), ("e_p", "e_p (m)"), ("e_phi", "e_phi (s)"),
           ("recognition", "recognition"), ("jump_p95", "jump p95 (rad)"),
           ("static_e_p", "static e_p (m)"), ("coverage", "coverage"))


def summarise(points: list[dict], keys: list[str], results: dict, failed: dict,
              data: dict) -> dict:
    """The summary of a sweep.

    Parameters
    ----------
    points, keys : list
        The grid's points and their configurations' keys, in grid order.
    results : dict
        Key -> stored result (``results/<key>.json``) of the finished configurations.
    failed : dict
        Key -> why the configuration failed.
    data : dict
        How the trials were obtained.
    """
    entries, seen = [], set()
    for point, key in zip(points, keys):
        if key in results and key not in seen:
            seen.add(key)
            entries.append({"key": key, "label": label(point), "point": results[key]["point"],
                            **results[key]["row"]})
    entries.sort(key=lambda e: (math.isnan(e["J"]), e["J"]))
    for rank, entry in enumerate(entries, 1):
        entry["rank"] = rank
    return {"data": data, "objective": OBJECTIVE, "n_configurations": len(set(keys)),
            "ranked": entries,
            "failed": [{"key": k, "label": label(points[keys.index(k)]), "error": e}
                       for k, e in failed.items()],
            "figure": "summary.png"}


def to_markdown(summary: dict) -> str:
    """The ranking as a Markdown table (best first), then the failed configurations."""
    ranked = summary["ranked"]
    lines = ["### Sweep", "", f"{len(ranked)} of {summary['n_configurations']} "
             f"configurations evaluated, ranked by {summary['objective']}.", "",
             "| rank | configuration | " + " | ".join(h for _, h in COLUMNS) + " |",
             "|---|---|" + "---|" * len(COLUMNS)]
    for e in ranked:
        cells = ["-" if e.get(k) is None else f"{e[k]:.3f}" for k, _ in COLUMNS]
        lines.append(f"| {e['rank']} | {e['label']} | " + " | ".join(cells) + " |")
    if summary["failed"]:
        lines += ["", "#### Failed", ""]
        lines += [f"- {f['label']}: {f['error']}" for f in summary["failed"]]
    return "\n".join(lines) + "\n"


def write_summary(out: str | Path, points: list[dict], keys: list[str], results: dict,
                  failed: dict, data: dict) -> dict:
    """Write ``summary.json``, ``summary.md`` and ``summary.png`` into ``out``; return the
    summary."""
    from sandbox.eval.evaluation import write_atomic
    from sandbox.eval.plots import plot_sweep

    out = Path(out)
    summary = summarise(points, keys, results, failed, data)
    write_atomic(out / "summary.json", json.dumps(summary, indent=1))
    write_atomic(out / "summary.md", to_markdown(summary))
    plot_sweep(summary, out / summary["figure"])
    return summary
