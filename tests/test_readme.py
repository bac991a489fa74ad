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


def test_the_two_commands_are_there():
    bash = "\n".join(_blocks("bash"))
    assert "python -m sandbox demo" in bash
    assert 'pip install -e ".[test]" && pytest' in bash


def test_demo_command_runs(tmp_path):
    out = subprocess.run([sys.executable, "-m", "sandbox", "demo"], capture_output=True,
                         text=True, cwd=tmp_path, timeout=600)
    assert out.returncode == 0, out.stderr
    assert "dynamic" in out.stdout and "static" in out.stdout
