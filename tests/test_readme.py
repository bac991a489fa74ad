"""The README: one screen, its two commands, and the reference pages the tests read.

Its Python and shell blocks run in ``tests/test_docs_blocks.py`` (with the docs' blocks).
"""

import re
import sys
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def _blocks(lang: str) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", README.read_text(), flags=re.S)


TEST_COMMAND = 'pip install -e ".[test,dask,minari,numba]" && pytest -n auto'


def test_the_two_commands_are_there():
    bash = "\n".join(_blocks("bash"))
    assert "python -m sandbox demo" in bash
    assert TEST_COMMAND in bash


def test_ci_runs_the_readme_test_command_exactly():
    """Optional extras are part of the test command, so CI installs and tests them too."""
    ci = README.parent / ".ci" / "run"
    assert ci.read_text().rstrip().splitlines()[-1] == TEST_COMMAND
    if sys.version_info >= (3, 11):
        import tomllib

        project = tomllib.loads((README.parent / "pyproject.toml").read_text())["project"]
        assert {"test", "dask", "minari", "numba"} <= set(project["optional-dependencies"])


DOCS = README.parent / "docs"


def _section(page: str, title: str) -> str:
    text = (DOCS / page).read_text()
    start = text.index(f"## {title}\n")
    end = text.find("\n## ", start + 1)
    return text[start:] if end < 0 else text[start:end]


def test_the_readme_fits_on_one_screen():
    """issue 24: the README is at most 200 lines; the rest is in docs/."""
    assert len(README.read_text().splitlines()) <= 200


def test_the_readme_results_are_the_generated_ones():
    """The README's results table is copied from what ``python -m sandbox results`` wrote
    (notebooks/figures/results.md), row by row, so it cannot drift from it."""
    generated = (README.parent / "notebooks" / "figures" / "results.md").read_text()
    rows = [line for line in _section_of_readme("Results in one table").splitlines()
            if line.startswith("| ") and "0." in line]
    assert len(rows) >= 4
    for row in rows:
        row = re.sub(r"^\| recorded \(\d+ trials\)", "| birl-handover-20180329", row)
        assert row in generated, row


def _section_of_readme(title: str) -> str:
    text = README.read_text()
    start = text.index(f"## {title}\n")
    return text[start:text.index("\n## ", start + 1)]


def test_the_scenario_format_documents_both_examples_and_every_key():
    """issue 14 part 1: the scenario-file format is in the README: the shipped examples as
    they are, and every key the loader accepts in the table."""
    import json

    import yaml

    from sandbox.episodes import scenario_files as sf

    section = _section("tutorials/viewer.md", "Scenario files")
    shown = [yaml.safe_load(b) for b in re.findall(r"```yaml\n(.*?)```", section, flags=re.S)]
    shown += [json.loads(b) for b in re.findall(r"```json\n(.*?)```", section, flags=re.S)]
    for example in sorted(sf.EXAMPLES.glob("*")):
        if example.suffix in sf.SUFFIXES:
            assert sf.read_mapping(example) in shown, example.name
    table = "\n".join(line for line in section.splitlines() if line.startswith("| `"))
    keys = {*sf.TOP_KEYS, *(f"model.{k}" for k in sf.MODEL_KEYS),
            *(f"human.{k}" for keys in sf.HUMAN_KEYS.values() for k in keys)}
    missing = sorted(k for k in keys if f"`{k}`" not in table)
    assert not missing


def test_the_settings_keys_are_documented():
    from sandbox.commands._settings import KEYS

    section = (DOCS / "tutorials" / "evaluate.md").read_text()
    assert [k for k in KEYS if k not in section] == []
