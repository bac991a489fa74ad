"""``python -m sandbox results``: regenerate the README's results (tables and figures).

Runs the leave-one-out evaluation on the synthetic diverging set (the paper's
Experiment 2), the synthetic object set, and, if ``--data`` is given, a recorded
set (Experiment 1); writes each ``report.json``, ``report.md`` and the figures to
``--figures``, and replaces the README text between ``<!-- results:start -->``
and ``<!-- results:end -->``. Nothing in those tables is typed by hand.
"""

from __future__ import annotations

NAME = "results"
HELP = "regenerate the README's results tables and figures from fresh evaluations"

START, END = "<!-- results:start -->", "<!-- results:end -->"


def add_arguments(parser) -> None:
    parser.add_argument("--data", default=None,
                        help="recorded set folder (e.g. ../shared/data/birl-handover-20180329)")
    parser.add_argument("--figures", default="notebooks/figures",
                        help="folder for reports and figures (default notebooks/figures)")
    parser.add_argument("--readme", default="README.md", help="README to update")
    parser.add_argument("--workers", type=int, default=2, help="processes")
    parser.add_argument("--seed", type=int, default=0, help="seed of the synthetic sets")


def run(args) -> int:
    import json
    from pathlib import Path

    from sandbox.eval.datasets import load_pair
    from sandbox.eval.loocv import EvalConfig, run_loocv
    from sandbox.eval.plots import plot_report
    from sandbox.eval.report import build_report, to_markdown

    out = Path(args.figures)
    out.mkdir(parents=True, exist_ok=True)
    readme = Path(args.readme)
    text = readme.read_text()
    if START not in text or END not in text:
        raise ValueError(f"{readme}: expected the markers {START} and {END}")
    sets = [("diverging", "synthetic:diverging"), ("objects", "synthetic:objects")]
    if args.data:
        sets.insert(0, ("recorded", args.data))
    reports = {}
    for name, spec in sets:
        train, test, _ = load_pair(spec, seed=args.seed)
        trials, runtime = run_loocv(train, test, EvalConfig(), workers=max(1, args.workers),
                                    progress=True)
        rep = build_report(trials, EvalConfig().to_dict(), spec, runtime)
        rep["dataset"] = spec if name != "recorded" else Path(spec).name
        (out / f"{name}.json").write_text(json.dumps(rep, indent=1))
        (out / f"{name}.md").write_text(to_markdown(rep))
        other = reports.get("recorded") if name == "diverging" else None
        plot_report(rep, out / name, other)
        reports[name] = rep
        print(f"{name}: {sum(rep['n_trials'].values())} trials in {runtime:.1f} s")
    body = [START, "", _summary_table(reports), ""]
    tune_table = out / "tune.md"
    if tune_table.is_file():
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
    head, rest = text.split(START, 1)
    readme.write_text(head + "\n".join(body) + rest.split(END, 1)[1])
    print(f"updated {readme}")
    return 0


def _summary_table(reports: dict) -> str:
    rows = ["| data | formulation | e_p (m) | e_q (rad) | e_phi (s) | recognition |",
            "|---|---|---|---|---|---|"]
    for rep in reports.values():
        for label, entry in (("oracle (floor)", rep["oracle"]["mean"]),
                             ("static, ratio 0.3", rep["static"]["0.3"]["mean"]),
                             ("static, ratio 0.5", rep["static"]["0.5"]["mean"]),
                             ("dynamic, dow_t 0.2 s", rep["dynamic"]["0.2"]["mean"]),
                             ("dynamic, dow_t 1.0 s", rep["dynamic"]["1.0"]["mean"])):
            rec = f"{entry['recognition']:.2f}" if "recognition" in entry else "(true task)"
            rows.append(f"| {rep['dataset']} | {label} | {entry['e_p']:.3f} | "
                        f"{entry['e_q']:.3f} | {entry['e_phi']:.3f} | {rec} |")
    return "\n".join(rows)
