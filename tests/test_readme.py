"""The README's code must work: its Python snippets run, its commands exist."""

import re
import subprocess
import sys
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"


def _blocks(lang: str) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", README.read_text(), flags=re.S)


@pytest.mark.parametrize("index", range(len(_blocks("python"))))
def test_python_snippets_run(index, tmp_path):
    code = _blocks("python")[index]
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=tmp_path, timeout=600)
    assert out.returncode == 0, out.stderr


TEST_COMMAND = 'pip install -e ".[test,dask,minari]" && pytest'


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
        assert {"test", "dask", "minari"} <= set(project["optional-dependencies"])


def test_demo_command_runs(tmp_path):
    out = subprocess.run([sys.executable, "-m", "sandbox", "demo"], capture_output=True,
                         text=True, cwd=tmp_path, timeout=600)
    assert out.returncode == 0, out.stderr
    assert "dynamic" in out.stdout and "static" in out.stdout


def _section(title: str) -> str:
    text = README.read_text()
    start = text.index(f"## {title}\n")
    return text[start:text.index("\n## ", start + 1)]


def test_the_scenario_format_documents_both_examples_and_every_key():
    """issue 14 part 1: the scenario-file format is in the README: the shipped examples as
    they are, and every key the loader accepts in the table."""
    import json

    import yaml

    from sandbox.episodes import scenario_files as sf

    section = _section("Scenario files")
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

    section = _section("Reusing a model and tuned settings")
    assert [k for k in KEYS if k not in section] == []
