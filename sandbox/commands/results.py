"""``python -m sandbox results``: regenerate the results (tables and figures).

Runs the leave-one-out evaluation on the synthetic diverging set (the paper's
Experiment 2), the synthetic object set, and, if ``--data`` is given, a recorded
set (Experiment 1, observing ``--observe``, default the hand) plus the
comparison of observation modalities on it (hand vs hand + arm vs hand + arm +
EMG, dynamic at 0.2 s, on the trials usable by all three); writes each
``report.json``, ``report.md``, the figures and ``results.md`` (the documentation's
results page, ``docs/results.md``, includes it from ``notebooks/figures``) to
``--out DIR`` (default: a fresh ``results-<date>-<time>`` folder; an existing folder that
is not empty needs ``--force``). Only with
``--update-readme`` does it replace the text of a README (``--readme``) between
``<!-- results:start -->`` and ``<!-- results:end -->`` (the figures linked
from there are those in ``--out``). Nothing in those tables is typed by hand.
To regenerate the documentation's results::

    python -m sandbox results --data ../shared/data/birl-handover-20180329 \
        --out notebooks/figures --force
"""

from __future__ import annotations

from sandbox.commands import _observation, _outputs, _types

NAME = "results"
HELP = "regenerate the results tables and figures (the docs' results page) from fresh evaluations"

START, END = "<!-- results:start -->", "<!-- results:end -->"


def add_arguments(parser) -> None:
    """Add the ``results`` command's options to ``parser``."""
    parser.add_argument("--data", default=None,
                        help="recorded set folder (e.g. ../shared/data/birl-handover-20180329)")
    parser.add_argument("--out", "--figures", dest="out", type=_types.output_folder,
                        default=None, metavar="DIR",
                        help="folder for the reports, figures and results.md (default: a "
                             "fresh results-<date>-<time> folder here)")
    _outputs.add_force(parser, "files in a non-empty --out folder")
    parser.add_argument("--update-readme", action="store_true",
                        help="also replace the results section of --readme (links to --out)")
    parser.add_argument("--readme", default="README.md",
                        help="README to update with --update-readme (default README.md)")
    parser.add_argument("--workers", type=_types.WORKERS, default=2,
                        help=f"processes, 1 to {_types.MAX_WORKERS} (default 2)")
    parser.add_argument("--seed", type=_types.SEED, default=0, help="seed of the synthetic sets")
    parser.add_argument("--compare", default="hand;hand,arm;hand,arm,emg", metavar="SETS",
                        help="observation sets compared on the recorded set, ';'-separated "
                             "(default hand;hand,arm;hand,arm,emg; 'none' to skip)")
    _observation.add_arguments(parser, columns=False)


def run(args) -> int:
    """Run ``python -m sandbox results`` with the parsed ``args``; return the exit status."""
    from pathlib import Path

    out = _out_folder(args)
    readme = Path(args.readme)
    text = _readme_text(readme) if args.update_readme else ""
    out.mkdir(parents=True, exist_ok=True)
    spec = _observation.data_spec(args)
    observe = _observation.observe(args, spec)
    reports = _evaluate_sets(args, out, spec, observe)
    section = "\n".join(_section(args, out, spec, reports))
    _outputs.write_text(out / "results.md", section[len(START):-len(END)].strip() + "\n")
    print(f"results: {out}/results.md")
    if args.update_readme:
        head, rest = text.split(START, 1)
        _outputs.write_text(readme, head + section + rest.split(END, 1)[1])
        print(f"updated {readme}")
    return 0


def _evaluate_sets(args, out, spec, observe) -> dict:
    """Leave-one-out of the recorded set (``--data``) and the synthetic ones: reports,
    tables and figures written to ``out``; returns the reports by set name."""
    import json
    from pathlib import Path

    from sandbox.eval.datasets import load_pair
    from sandbox.eval.loocv import EvalConfig, run_loocv
    from sandbox.eval.plots import plot_report
    from sandbox.eval.report import build_report, to_markdown

    sets = [("diverging", "synthetic:diverging"), ("objects", "synthetic:objects")]
    if args.data:
        sets.insert(0, ("recorded", args.data))
    reports = {}
    for name, data in sets:
        recorded = name == "recorded"
        config = EvalConfig(observe=observe if recorded else None)
        train, test, _ = load_pair(data, seed=args.seed, spec=spec if recorded else None,
                                   observe=observe if recorded else None)
        trials, runtime = run_loocv(train, test, config, workers=args.workers,
                                    progress=True)
        rep = build_report(trials, config.to_dict(), data, runtime)
        rep["dataset"] = data if name != "recorded" else Path(data).name
        _outputs.write_text(out / f"{name}.json", json.dumps(rep, indent=1))
        _outputs.write_text(out / f"{name}.md", to_markdown(rep))
        other = reports.get("recorded") if name == "diverging" else None
        plot_report(rep, out / name, other)
        reports[name] = rep
        print(f"{name}: {sum(rep['n_trials'].values())} trials in {runtime:.1f} s")
    return reports


def _section(args, out, spec, reports: dict) -> list[str]:
    """The lines of the README's results section, START to END (the modality comparison
    of ``--compare`` is computed here)."""
    from pathlib import Path

    from sandbox.eval.report import to_markdown

    body = [START, "", _summary_table(reports), ""]
    compare = _compare_sets(args.compare)
    if args.data and compare:
        table = compare_modalities(args.data, spec, compare, workers=args.workers,
                                   figures=out / "recorded")
        _outputs.write_text(out / "modalities.md", table)
        rel = (out / "recorded").as_posix()
        body += [f"#### Observation modalities on `{Path(args.data).name}` (dynamic, dow_t = "
                 "0.2 s; 95 % bootstrap intervals; recognition over the whole recording, "
                 "idle tail included)", "", table, "",
                 f"![recognition by observation]({rel}/modalities.png)",
                 f"![the late-motion fix taken apart]({rel}/late_motion.png)", ""]
    tune_table = out / "tune.md"
    if not tune_table.is_file():
        print(f"no {tune_table}: the section leaves out the cross-validation of the defaults "
              f"(python -m sandbox tune --data DIR --markdown {tune_table} adds it)")
    else:
        body += ["<details><summary>Cross-validation of the defaults "
                 "(<code>python -m sandbox tune</code>, dynamic at dow_t = 0.2 s)</summary>", "",
                 tune_table.read_text(), "</details>", ""]
    for name, rep in reports.items():
        rel = (out / name).as_posix()
        body += [f"<details><summary>All tables: {rep['dataset']}</summary>", "",
                 to_markdown(rep), "</details>", "",
                 f"![{name}: direct evaluation]({rel}/direct.png)",
                 f"![{name}: comparative evaluation]({rel}/comparative.png)",
                 f"![{name}: recognition]({rel}/recognition.png)", ""]
    if "recorded" in reports:
        body.append(f"![Experiment 1 vs 2]({(out / 'diverging').as_posix()}"
                    "/average_comparison.png)\n")
    body.append(END)
    return body


def _out_folder(args):
    """``--out``, checked (not empty needs ``--force``), or a fresh folder's name."""
    import time
    from pathlib import Path

    if args.out is None:
        stamp = time.strftime("%Y%m%d-%H%M%S")
        out, n = Path(f"results-{stamp}"), 1
        while out.exists():
            n += 1
            out = Path(f"results-{stamp}-{n}")
        return out
    _outputs.check_folder("--out", args.out, args.force)
    return Path(args.out)


def _readme_text(readme) -> str:
    """The README to update, checked before any work (it has the markers, can be written)."""
    import os

    try:
        text = readme.read_text(encoding="utf-8")
    except OSError as error:
        raise ValueError(f"--readme: cannot read {readme} ({error.strerror})") from None
    if START not in text or END not in text:
        raise ValueError(f"--readme: expected the markers {START} and {END} in {readme}")
    if not os.access(readme, os.W_OK):
        raise ValueError(f"--readme: {readme} is not writable")
    return text


def _summary_table(reports: dict) -> str:
    from sandbox.eval.report import fmt  # "n/a" for e_q in task space

    rows = ["| data | formulation | e_p (m) | e_q (rad) | e_phi (s) | recognition "
            "(task-averaged) |",
            "|---|---|---|---|---|---|"]
    for rep in reports.values():
        for label, entry in (("oracle (floor)", rep["oracle"]["mean"]),
                             ("static, ratio 0.3", rep["static"]["0.3"]["mean"]),
                             ("static, ratio 0.5", rep["static"]["0.5"]["mean"]),
                             ("dynamic, dow_t 0.2 s", rep["dynamic"]["0.2"]["mean"]),
                             ("dynamic, dow_t 1.0 s", rep["dynamic"]["1.0"]["mean"])):
            rec = f"{entry['recognition']:.2f}" if "recognition" in entry else "(true task)"
            rows.append(f"| {rep['dataset']} | {label} | {entry['e_p']:.3f} | "
                        f"{fmt(entry['e_q'])} | {entry['e_phi']:.3f} | {rec} |")
    return "\n".join(rows)


def _compare_sets(text: str) -> list[tuple[str, ...]]:
    if text.strip().lower() == "none":
        return []
    sets = [tuple(n.strip() for n in part.split(",") if n.strip()) for part in text.split(";")]
    if not all(sets):
        raise ValueError(f"--compare: expected ';'-separated lists of modalities, got {text!r}")
    return sets


#: The late-motion fix taken apart (options of EvalConfig), for the hand alone.
ABLATIONS = (
    ("hand, whole recordings as the motion", {"settle_tol": None, "arrive_tol": None}),
    ("hand, task re-chosen to the end", {"until_end": False}),
    ("hand, neither (no late-motion fix)", {"settle_tol": None, "arrive_tol": None,
                                            "until_end": False}),
)


def compare_modalities(data: str, spec, sets, *, workers: int = 2, window: float = 0.2,
                       figures=None) -> str:
    """Leave-one-out of each observation set on the same trials; Markdown tables.

    The trials are loaded once with every modality of ``sets`` (a trial any of
    them cannot use is left out of all), and each row observes its subset. If
    ``hand`` is observed, the late-motion fix is then taken apart on the hand
    alone (:data:`ABLATIONS`). ``figures``: a folder for ``modalities.png`` and
    ``late_motion.png`` (recognition over the recording of each row).
    """
    from dataclasses import replace

    from sandbox.eval.datasets import load_pair
    from sandbox.eval.loocv import EvalConfig
    from sandbox.eval.plots import plot_curves

    every = tuple(dict.fromkeys(n for names in sets for n in names))
    train, test, _ = load_pair(data, spec=spec, observe=every)
    runs = {",".join(names): EvalConfig(windows=(window,), ratios=(0.3,), observe=names)
            for names in sets}
    reports = {label: _evaluate(train, test, config, data, workers, f"observe {label}")
               for label, config in runs.items()}
    tables = _table(reports, window)
    if "hand" in every:
        hand = EvalConfig(windows=(window,), ratios=(0.3,), observe=("hand",))
        fixed = "hand (the fix as defined)"
        late = {fixed: reports.get("hand") or _evaluate(train, test, hand, data, workers, fixed)}
        for label, options in ABLATIONS:
            late[label] = _evaluate(train, test, replace(hand, **options), data, workers,
                                    label)
        tables += "\n" + _table(late, window)
    if figures is not None:
        w = f"{window:.1f}"
        plot_curves(reports, f"{figures}/modalities.png", w,
                    "Recognition over the recording, by observation")
        if "hand" in every:
            plot_curves(late, f"{figures}/late_motion.png", w,
                        "Recognition over the recording: the late-motion fix taken apart")
    return tables


def _evaluate(train, test, config, data, workers, label: str) -> dict:
    from sandbox.eval.loocv import run_loocv
    from sandbox.eval.report import build_report

    trials, runtime = run_loocv(train, test, config, workers=workers, progress=True)
    print(f"{label}: {len(trials)} trials in {runtime:.1f} s")
    return build_report(trials, config.to_dict(), data, runtime)


def _table(reports: dict, window: float) -> str:
    from sandbox.eval.report import fmt  # "n/a" for e_q in task space

    rows = ["| observe | e_p (m) | e_q (rad) | e_phi (s) | recognition at 30 % (share of "
            "trials) | at the end | late decay (peak - end) | wall (s) |",
            "|---|---|---|---|---|---|---|---|"]
    w = f"{window:.1f}"
    for label, rep in reports.items():
        d, c = rep["dynamic"][w]["mean"], rep["recognition_over_time_ci"][w]
        at = list(rep["recognition_over_time"]["fractions"]).index(0.3)
        cells = [fmt(d[k]) if d[k] is None else
                 f"{d[k]:.3f} [{d[k + '_ci'][0]:.3f}, {d[k + '_ci'][1]:.3f}]"
                 for k in ("e_p", "e_q", "e_phi")]
        cells += [f"{c['mean'][at]:.2f} [{c['lo'][at]:.2f}, {c['hi'][at]:.2f}]",
                  f"{c['mean'][-1]:.2f} [{c['lo'][-1]:.2f}, {c['hi'][-1]:.2f}]",
                  f"{c['decay']:.3f} [{c['decay_ci'][0]:.3f}, {c['decay_ci'][1]:.3f}]",
                  f"{rep['runtime_s']:.0f}"]
        rows.append(f"| {label} | " + " | ".join(cells) + " |")
    return "\n".join(rows) + "\n"
