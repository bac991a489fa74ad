"""``python -m sandbox plot REPORT.json [REPORT2.json] --out DIR``: the paper's figures.

Existing figure files in ``--out`` are replaced only with ``--force``.
"""

from __future__ import annotations

from sandbox.commands import _outputs, _types

NAME = "plot"
HELP = "draw the evaluation figures (PNG) of one report, or compare two"


def add_arguments(parser) -> None:
    """Add the ``plot`` command's options to ``parser``."""
    parser.add_argument("reports", nargs="+", help="report.json (a second one to compare)")
    parser.add_argument("--out", type=_types.output_folder, required=True,
                        help="folder for the PNG files")
    _outputs.add_force(parser, "figure files in --out")


def run(args) -> int:
    """Run ``python -m sandbox plot`` with the parsed ``args``; return the exit status."""
    import json
    from pathlib import Path

    from sandbox.eval.plots import plot_report

    if len(args.reports) > 2:
        raise ValueError(f"expected one or two reports, got {len(args.reports)}")
    _outputs.check_new([("--out", f) for f in _outputs.figures(args.out, len(args.reports) > 1)],
                       args.force)
    reports = []
    for name in args.reports:
        path = Path(name)
        try:
            reports.append(json.loads(path.read_text()))
        except (OSError, json.JSONDecodeError) as error:
            raise ValueError(
                f"{name}: expected a report.json written by evaluate ({error})") from None
        if not {"static", "dynamic", "oracle", "tasks"} <= set(reports[-1]):
            raise ValueError(f"{name}: not a report written by 'python -m sandbox evaluate'")
    other = reports[1] if len(reports) > 1 else None
    for path in plot_report(reports[0], args.out, other):
        print(path)
    return 0
