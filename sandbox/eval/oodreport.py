"""The ``ood`` report: detection at fixed false-alarm rates, AUC and delays, from ranked records.

A ranked record (:func:`sandbox.eval.ood.rank`, or
:func:`sandbox.eval.oodsets.score_with_model`) is one motion: its update
``times`` (s), its ``familiarity`` at each (in (0, 1], low = unlike the
training motions), ``end`` (the handover moment, s), whether it is normal
(``held_in``) and its ``group`` (an OOD set, or the left-out task).

* **Score of a motion:** its lowest familiarity at the updates up to the
  handover (none: it is never flagged). A motion is flagged at threshold
  ``h`` when its score is below ``h``.
* **Detection at a false-alarm rate a** (:data:`FA_RATES`): ``h`` is the
  largest threshold that flags at most a share ``a`` of the group's *normal*
  motions (held out of every fit and calibration that scores them); the
  detection is the share of OOD motions it flags, before the handover.
* **AUC:** the probability that an OOD motion scores lower than a normal one
  (ties count one half).
* **Delay:** per motion detected at ``h``, the first update below ``h`` minus
  the handover moment (s; negative: before the handover); the report gives
  their median and quartiles.
* **Calibrated:** the calibration's own threshold at ``alpha`` (what a robot
  running the model uses), as false alarms / detection at any update of the
  recording and at updates up to the handover.
"""

from __future__ import annotations

import numpy as np

from sandbox.core.conformal import conformal_threshold

#: False-alarm rates the detection is reported at.
FA_RATES = (0.01, 0.02, 0.05, 0.10)
#: Rules of the calibrated threshold: updates of the whole recording, or up to the handover.
CALIBRATED_RULES = ("any update", "before the handover")
#: Name of the pooled group.
ALL = "all"


def group_of(record: dict) -> str:
    """The group a record is reported in: its OOD set or its left-out task."""
    group = record.get("group")
    return str(record["left_out"] if group is None and "group" not in record else group)


def score(record: dict) -> float:
    """Lowest familiarity at the updates up to the handover (inf: none)."""
    t, fam = np.asarray(record["times"], dtype=float), np.asarray(record["familiarity"],
                                                                  dtype=float)
    before = fam[(t <= record["end"] + 1e-9) & np.isfinite(fam)]
    return float(before.min()) if before.size else float("inf")


def auc(normal, ood) -> float:
    """P(OOD score < normal score) + P(equal) / 2 (NaN if a side is empty)."""
    a, b = np.asarray(ood, dtype=float)[:, None], np.asarray(normal, dtype=float)[None, :]
    if a.size == 0 or b.size == 0:
        return float("nan")
    return float(np.mean((a < b) + 0.5 * (a == b)))


def threshold_at(normal, rate: float) -> float:
    """Largest threshold flagging (score < threshold) at most ``rate`` of ``normal`` scores."""
    s = np.sort(np.asarray(normal, dtype=float))
    k = int(np.floor(rate * s.size + 1e-9))
    return float(s[min(k, s.size - 1)]) if k < s.size else float("inf")


def first_flag(record: dict, threshold: float) -> float | None:
    """Time (s) of the first update whose familiarity is below ``threshold`` (None: none)."""
    fam = np.asarray(record["familiarity"], dtype=float)
    low = np.flatnonzero(np.isfinite(fam) & (fam < threshold))
    return float(record["times"][low[0]]) if low.size else None


def operating_point(normal: list[dict], ood: list[dict], rate: float) -> dict:
    """Threshold, false alarms, detection and delays at false-alarm rate ``rate``."""
    s_normal, s_ood = [score(r) for r in normal], [score(r) for r in ood]
    h = threshold_at(s_normal, rate)
    detected = [r for r, s in zip(ood, s_ood) if s < h]
    delays = [first_flag(r, h) - r["end"] for r in detected]  # type: ignore[operator]
    q = np.quantile(delays, [0.25, 0.5, 0.75]).tolist() if delays else [float("nan")] * 3
    return {"threshold": h, "false_alarm": float(np.mean(np.array(s_normal) < h)),
            "detection": len(detected) / len(ood) if ood else float("nan"),
            "median_delay_s": q[1], "delay_quartiles_s": [q[0], q[2]]}


def calibrated(records: list[dict], alpha: float) -> dict:
    """Per rule, share of ``records`` flagged by the calibration's threshold at ``alpha``."""
    out = {}
    for rule in CALIBRATED_RULES:
        flags = []
        for r in records:
            h = (conformal_threshold(r["reference"], alpha) if r.get("reference") is not None
                 else float(r["threshold"]))
            t, fam = np.asarray(r["times"], dtype=float), np.asarray(r["familiarity"], float)
            keep = np.isfinite(fam) & ((t <= r["end"] + 1e-9) if rule != "any update" else True)
            flags.append(bool(np.any(fam[keep] < h)))
        out[rule] = float(np.mean(flags)) if flags else float("nan")
    return out


def groups(records: list[dict]) -> dict[str, tuple[list[dict], list[dict]]]:
    """Normal and OOD records of every group, and of all groups pooled (:data:`ALL`).

    A group's normal records are the held-in records of that group (leave-task-out:
    the trained tasks' motions of that fold) or, when the normal records have no
    group (OOD sets), all of them.
    """
    shared = [r for r in records if r["held_in"] and r.get("group", "") is None]
    out = {}
    for g in sorted({group_of(r) for r in records if not r["held_in"]}):
        own = [r for r in records if r["held_in"] and group_of(r) == g]
        out[g] = (own or shared, [r for r in records if not r["held_in"] and group_of(r) == g])
    if len(out) > 1:
        out[ALL] = ([r for r in records if r["held_in"]],
                    [r for r in records if not r["held_in"]])
    return out


def summarize(records: list[dict], *, alpha: float = 0.05, rates=FA_RATES) -> dict:
    """Per group: sizes, AUC, :func:`operating_point` at each rate, :func:`calibrated`."""
    out = {}
    for g, (normal, ood) in groups(records).items():
        s_n, s_o = [score(r) for r in normal], [score(r) for r in ood]
        cal_n, cal_o = calibrated(normal, alpha), calibrated(ood, alpha)
        out[g] = {"n_normal": len(normal), "n_ood": len(ood), "auc": auc(s_n, s_o),
                  "at_false_alarm": {f"{a:g}": operating_point(normal, ood, a) for a in rates},
                  "calibrated": {rule: {"false_alarm": cal_n[rule], "detection": cal_o[rule]}
                                 for rule in CALIBRATED_RULES}}
    return out


def roc(normal: list[dict], ood: list[dict]) -> tuple[np.ndarray, np.ndarray]:
    """False-alarm and detection rates (before the handover) over all thresholds, from (0, 0)."""
    s_n = np.array([score(r) for r in normal])
    s_o = np.array([score(r) for r in ood])
    cuts = np.unique(np.concatenate([s_n, s_o, [np.inf]]))
    fa = np.array([0.0] + [np.mean(s_n < h) for h in cuts] + [1.0])
    det = np.array([0.0] + [np.mean(s_o < h) for h in cuts] + [1.0])
    return fa, det


def _seconds(value: float) -> str:
    return "n/a" if not np.isfinite(value) else f"{value:+.2f}"


def markdown(result: dict) -> str:
    """The report's tables (one row per group)."""
    rates = list(next(iter(result["groups"].values()))["at_false_alarm"]) if result[
        "groups"] else []
    a = result["alpha"]
    lines = [f"{result['mode']} on `{result['data']}`"
             + (f" against {', '.join(f'`{s}`' for s in result['ood_data'])}"
                if result.get("ood_data") else "")
             + f" (observe {result['observe']}; dow_t = {result['dow_t']:g} s"
             + (f"; score {result['score']}" if result.get("score") else "")
             + (f"; cells of the {result['cells']} task" if result.get("cells") else "")
             + (f"; until the estimated end, P >= {result['end_prob']:g}"
                if result.get("end_prob") is not None else "") + "); "
             f"{result['n_streams']} streams, {result['seconds']:.0f} s.", "",
             "Detection before the handover at a false-alarm rate on held-out normal motions:",
             "", "| OOD | normal | OOD motions | AUC | "
             + " | ".join(f"detection @ {100 * float(r):g} % FA" for r in rates)
             + " | median delay @ 5 % FA (s) | calibrated alpha "
             f"{a:g}: FA / detection (any update) | (before the handover) |",
             "|---|---|---|---|" + "---|" * len(rates) + "---|---|---|"]
    for g, v in result["groups"].items():
        at = v["at_false_alarm"]
        delay = at.get("0.05", {}).get("median_delay_s", float("nan"))
        cal = [f"{v['calibrated'][rule]['false_alarm']:.3f} / "
               f"{v['calibrated'][rule]['detection']:.3f}" for rule in CALIBRATED_RULES]
        lines.append(f"| {g} | {v['n_normal']} | {v['n_ood']} | {v['auc']:.3f} | "
                     + " | ".join(f"{at[r]['detection']:.3f}" for r in rates)
                     + f" | {_seconds(delay)} | {cal[0]} | {cal[1]} |")
    return "\n".join(lines) + "\n"
