"""Cross-validated choice of the defaults the core leaves open.

Coordinate descent over a few options, each evaluated by leave-one-out on a
dataset with the dynamic formulation at ``window`` (and the static one at
``ratio`` for reference). The objective, normalised by the evaluation targets,
is

.. math::  J = e_p / 0.05\\,m + e_\\phi / 0.20\\,s + (1 - \\text{recognition}) / 0.30
           + \\max(0, j_{95} - 0.01\\,rad) / 0.01\\,rad,

lower is better, where :math:`j_{95}` is the 95th percentile of the command jump
at updates (the command must stay continuous). Each option is swept in turn
with the others at their best so far; a value replaces the current one only if
it lowers J by more than ``tol`` (0.05, about the trial-to-trial noise of J),
so the defaults do not chase noise. The table of every run is returned.

The configurations of each step are evaluated together by
:class:`~sandbox.eval.evaluation.Evaluation`, on local processes or a Dask cluster
(``scheduler``, see :func:`~sandbox.eval.executors.open_executor`).
"""

from __future__ import annotations

import sys
from dataclasses import replace

from sandbox.eval.loocv import EvalConfig

#: Options swept, in order, with their candidate values.
GRID: dict[str, tuple] = {
    "noise_floor": (0.001, 0.005, 0.01, 0.02, 0.04),
    "regularizer": (1e-4, 1e-3, 1e-2, 1e-1),
    "likelihood": ("joint", "marginal"),
    "window_mode": ("all", "latest"),
    "n_basis": (15, 21, 31),
    "blend_rate": (20.0, 50.0, 100.0),
}
TARGETS = {"e_p": 0.05, "e_phi": 0.20, "miss": 0.30, "jump": 0.01}
#: Dynamic window dow_t (s) scored by J, and observed ratio reported for the static formulation.
WINDOW = 0.2
RATIO = 0.3
#: Floors (normalised units) tried for signal modalities, and (m) for position
#: modalities other than the hand, when they are observed.
SIGNAL_FLOORS = (0.1, 0.3, 0.5, 1.0)
POSITION_FLOORS = (0.01, 0.02, 0.04)


def grid_for(modalities) -> dict[str, tuple]:
    """The options to sweep for these modalities (names or Modality objects; names
    other than the built-ins count as positions): :data:`GRID`, ``settle_tol``, plus
    ``signal_floor`` if a signal is observed and a floor per other position modality."""
    from sandbox.data.spec import BUILT_IN

    mods = [BUILT_IN.get(m, None) if isinstance(m, str) else m for m in modalities]
    names = [m if isinstance(m, str) else m.name for m in modalities]
    grid = dict(GRID)
    grid["settle_tol"] = (None, 0.01, 0.02, 0.05)
    if any(m is not None and m.kind == "signal" for m in mods):
        grid["signal_floor"] = SIGNAL_FLOORS
    others = [n for n, m in zip(names, mods) if n != "hand" and (m is None or
                                                                m.kind == "position")]
    if others:
        grid["noise_floors"] = tuple(tuple((n, f) for n in others) for f in POSITION_FLOORS)
    return grid


def objective(entry: dict, jump_p95: float = 0.0) -> float:
    """J of a report's ``dynamic[window]["mean"]`` entry and jump percentile (rad)."""
    return (entry["e_p"] / TARGETS["e_p"] + entry["e_phi"] / TARGETS["e_phi"]
            + (1.0 - entry["recognition"]) / TARGETS["miss"]
            + max(0.0, jump_p95 - TARGETS["jump"]) / TARGETS["jump"])


def tune(train, test, *, base: EvalConfig | None = None, grid: dict | None = None,
         window: float = WINDOW, ratio: float = RATIO, workers: int = 2, tol: float = 0.05,
         log=print, scheduler: str | None = None, timeout: float | None = None,
         progress: bool = False) -> tuple:
    """Sweep ``grid`` from ``base``; returns (best config, rows of the table).

    ``workers``, ``scheduler`` and ``timeout`` choose where the leave-one-out
    runs (:func:`~sandbox.eval.executors.open_executor`). A configuration whose
    evaluation failed (its worker died twice) is logged and is not a candidate.
    ``progress`` draws a bar of the leave-one-out trials on stderr (at most one
    run per grid value; a value equal to the current choice is not re-run, and
    the bar's total shrinks by it).
    """
    from sandbox.eval.evaluation import Evaluation
    from sandbox.eval.executors import TIMEOUT, open_executor
    from sandbox.eval.progress import bar

    grid = GRID if grid is None else grid
    best = replace(base or EvalConfig(), windows=(window,), ratios=(ratio,))
    seen: dict = {}
    rows = []
    n_runs = sum(len(values) for values in grid.values())
    with open_executor(workers, scheduler, TIMEOUT if timeout is None else timeout) as ex, \
            bar(n_runs * len(train), f"tune ({n_runs} runs)", progress) as shown:
        evaluation = Evaluation(ex)
        token = evaluation.add(train, test)
        for name, values in grid.items():
            configs = [replace(best, **{name: value}) for value in values]
            fresh = [(c, token) for c in configs if _key(c) not in seen]
            repeated = len(configs) - len(fresh)
            if repeated:
                shown.total -= repeated * len(train)
                shown.refresh()
            shown.set_postfix_str(name)
            done = {_key(e.config): (e.report, e.error)
                    for e in evaluation.run(fresh, on_trials=shown.update)}
            scores = {}
            for value, cfg in zip(values, configs):
                key = _key(cfg)
                if key not in seen:
                    rep, error = done[key]
                    seen[key] = None if rep is None else _row(rep, cfg, window, ratio, name,
                                                              value)
                    line = (f"failed: {name}={value} ({error})" if seen[key] is None
                            else _format(seen[key]))
                    if seen[key] is not None:
                        rows.append(seen[key])
                    with shown.external_write_mode(file=sys.stdout):   # not through the bar
                        log(line)
                if seen[key] is not None:
                    scores[value] = seen[key]["J"]
            best = _step(best, name, scores, tol)
    return best, rows


def _key(cfg: EvalConfig) -> tuple:
    return tuple(sorted(cfg.to_dict().items()))


def _step(best: EvalConfig, name: str, scores: dict, tol: float) -> EvalConfig:
    """``best`` with ``name`` set to the value of lowest J if it beats the current by ``tol``."""
    if not scores:
        return best
    current = getattr(best, name)
    winner = min(scores, key=scores.get)
    if current not in scores or scores[winner] < scores[current] - tol:
        best = replace(best, **{name: winner})
    return best


def _row(rep: dict, cfg: EvalConfig, window: float, ratio: float, name: str, value) -> dict:
    return {"swept": name, "value": value, **config_row(rep, cfg, window, ratio)}


def config_row(rep: dict, cfg: EvalConfig, window: float = WINDOW, ratio: float = RATIO) -> dict:
    """The options and measures of one configuration's report, with its objective ``J``.

    ``rep`` is the :func:`~sandbox.eval.report.build_report` of ``cfg``, which
    evaluated the dynamic formulation at ``window`` and the static one at ``ratio``.
    """
    d = rep["dynamic"][f"{window:.1f}"]["mean"]
    s = rep["static"][f"{ratio:.1f}"]["mean"]
    return {
        "observe": ",".join(cfg.observe or ("hand",)),
        "noise_floor": cfg.noise_floor, "signal_floor": cfg.signal_floor,
        "noise_floors": ",".join(f"{n}:{f:g}" for n, f in cfg.noise_floors) or "-",
        "settle_tol": cfg.settle_tol, "regularizer": cfg.regularizer,
        "likelihood": cfg.likelihood, "window_mode": cfg.window_mode, "n_basis": cfg.n_basis,
        "blend_rate": cfg.blend_rate, "jump_p95": rep["jumps"][f"{window:.1f}"].get("p95"),
        "e_p": d["e_p"], "e_q": d["e_q"], "e_phi": d["e_phi"], "recognition": d["recognition"],
        "recognition_30": rep["recognition_over_time"][f"{window:.1f}"][2],
        "late_decay": late_decay(rep["recognition_over_time"][f"{window:.1f}"]),
        "coverage": d["coverage"], "static_e_p": s["e_p"],
        "static_recognition": s["recognition"], "oracle_e_p": rep["oracle"]["mean"]["e_p"],
        "J": objective(d, rep["jumps"][f"{window:.1f}"].get("p95", 0.0)),
        "runtime_s": rep["runtime_s"],
    }


HEADER = ("swept", "observe", "noise_floor", "signal_floor", "noise_floors", "settle_tol",
          "regularizer", "likelihood", "window_mode", "n_basis", "blend_rate", "e_p", "e_q",
          "e_phi", "recognition", "recognition_30", "late_decay", "coverage", "jump_p95",
          "static_e_p", "oracle_e_p", "J")


def late_decay(curve) -> float:
    """Peak minus end of a recognition-over-time curve (0 when it never falls)."""
    return float(max(curve) - curve[-1])


def _format(row: dict) -> str:
    cells = []
    for key in HEADER:
        v = row[key]
        cells.append(f"{v:.3g}" if isinstance(v, float) else str(v))
    return "| " + " | ".join(cells) + " |"


def table(rows: list[dict]) -> str:
    """Markdown table of a tuning run."""
    head = "| " + " | ".join(HEADER) + " |\n|" + "---|" * len(HEADER) + "\n"
    return head + "\n".join(_format(r) for r in rows) + "\n"
