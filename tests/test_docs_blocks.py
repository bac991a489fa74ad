"""Every Python and shell block of the README and the docs runs as written (issue 27, 1-2).

Each document's blocks run in order, in a fresh folder of their own, as a reader pasting
them would: a ``python`` block is saved as a script and run (so a vector env needs its
``if __name__ == "__main__":`` guard, as in a file), a ``bash`` block runs in bash with
``set -e``, and a ``yaml`` block whose first line is a comment naming a file
(``# grid.yaml``) is saved under that name for the blocks after it. ``text`` blocks
(interactive teleop, a cluster's commands, Gymnasium's ``play`` window) are not run.

What differs from a reader's run, and why:

- ``pip install ...`` is not run: the suite runs after that install. The test command
  itself (``... && pytest``) and the docs build are checked elsewhere:
  ``tests/test_readme.py`` holds ``.ci/run``'s last line to the README's test command,
  and :func:`test_ci_builds_the_docs_as_the_readme_says` the build command;
- ``../shared/data`` is the checkout's recorded data (``SANDBOX_DATA`` or
  ``../shared/data``); without it such a document skips (fails under
  ``SANDBOX_REQUIRE_DATA=1``);
- :data:`SHORTER` cuts the blocks that would take minutes on the recorded set to a few
  trials or episodes (the options exist for users too);
- Minari datasets go to a folder of the test (``MINARI_DATASETS_PATH``), not ``~/.minari``.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import RECORDED_SET, _missing, recorded_root

REPO = Path(__file__).resolve().parents[1]
DOCS = REPO / "docs"
DOCUMENTS = [REPO / "README.md", *sorted(p for p in DOCS.rglob("*.md")
                                         if not {"_build", "_generated"} & set(p.parts))]
BLOCK = re.compile(r"^```(\S*)[^\n]*\n(.*?)^```", flags=re.S | re.M)
RUN = {"python", "bash"}
#: (pattern, replacement, why): applied to each shell line that reads the recorded set or
#: runs many episodes, so that a document runs in seconds instead of minutes.
SHORTER = [
    (r"^(python -m sandbox (?:evaluate|fit|tune|sweep|compare|data export) "
     r".*--data \.\./shared/\S*)",
     r"\1 --n-per-task 4", "the recorded set: 4 trials per task (174 in all)"),
    (r"^(python -m sandbox evaluate .*--data \.\./shared/.*)$",
     r"\1 --windows 0.2 --ratios 0.5", "leave-one-out at one window and one ratio"),
    (r"^(python -m sandbox tune .*--data \.\./shared/.*)$",
     r"\1 --tasks gummed_paper,pencil_box --n-per-task 3", "tune: 2 tasks, 3 trials each"),
    (r"--episodes \d+", "--episodes 2", "2 episodes per policy instead of 20"),
]
NOT_RUN = {
    'pip install -e ".[test,dask,minari,numba]" && pytest -n auto':
        "the test command: .ci/run's last line",
    "sphinx-build -W --keep-going -n -b html docs docs/_build/html": ".ci/run builds the docs",
}


def blocks(path: Path) -> list[tuple[str, str]]:
    """(language, code) of every fenced block of ``path``, in order."""
    return [(m.group(1), m.group(2)) for m in BLOCK.finditer(path.read_text())]


def shell_lines(code: str, data: Path) -> list[str]:
    """The lines of a shell block as the test runs them (see the module docstring)."""
    out = []
    for line in code.splitlines():
        stripped = line.strip()
        if not stripped or stripped.startswith("#") or stripped in NOT_RUN:
            continue
        stripped = re.sub(r"^pip install -e \.(?:\[[\w,]+\])? && ", "", stripped)
        if stripped.startswith("pip install"):
            continue
        for pattern, replacement, _ in SHORTER:
            stripped = re.sub(pattern, replacement, stripped)
        stripped = stripped.replace("../shared/data", str(data))
        out.append(stripped.replace("python -m sandbox", f"{sys.executable} -m sandbox"))
    return out


def _needs_data(path: Path) -> bool:
    return any("../shared/data" in code for lang, code in blocks(path) if lang in RUN)


def _run(argv: list[str], folder: Path, env: dict, what: str) -> None:
    out = subprocess.run(argv, cwd=folder, env=env, capture_output=True, text=True,
                         timeout=900)
    assert out.returncode == 0, f"{what} failed:\n{out.stdout[-2000:]}\n{out.stderr[-4000:]}"


@pytest.mark.slow
@pytest.mark.parametrize("document", DOCUMENTS, ids=lambda p: str(p.relative_to(REPO)))
def test_every_block_runs_in_order(document, tmp_path):
    data = recorded_root()
    if _needs_data(document) and not (data / RECORDED_SET).is_dir():
        _missing(f"the recorded handovers ({data / RECORDED_SET})", "SANDBOX_REQUIRE_DATA")
    env = {**os.environ, "MINARI_DATASETS_PATH": str(tmp_path / ".minari"),
           "OPENBLAS_NUM_THREADS": os.environ.get("OPENBLAS_NUM_THREADS", "1")}
    for i, (lang, code) in enumerate(blocks(document)):
        first = code.splitlines()[0] if code.strip() else ""
        if lang == "yaml" and re.fullmatch(r"# [\w.-]+\.ya?ml", first.strip()):
            (tmp_path / first[2:].strip()).write_text(code)
        elif lang == "python":
            script = tmp_path / f"block_{i}.py"
            script.write_text(code)
            _run([sys.executable, script.name], tmp_path, env, f"python block {i}:\n{code}")
        elif lang == "bash":
            lines = shell_lines(code, data)
            if lines:
                _run(["bash", "-euo", "pipefail", "-c", "\n".join(lines)], tmp_path, env,
                     f"shell block {i}:\n" + "\n".join(lines))


def test_shell_blocks_name_only_commands_that_exist():
    """A shell block runs ``python -m sandbox`` commands (or installs): nothing else hides in
    them, and every command named is one the CLI has."""
    from sandbox.cli import build_parser

    commands = set(build_parser()._subparsers._group_actions[0].choices)
    for document in DOCUMENTS:
        for lang, code in blocks(document):
            if lang != "bash":
                continue
            for line in shell_lines(code, Path("DATA")):
                assert line.startswith(f"{sys.executable} -m sandbox "), (document, line)
                assert line.split()[3] in commands, (document, line)


def test_every_block_is_run_or_says_why_not():
    """Blocks are python, bash, yaml/json (data) or text (not run): a ``sh``, ``console`` or
    unlabelled block would be skipped silently."""
    allowed = {"python", "bash", "yaml", "json", "text"}
    found = {(doc.name, lang) for doc in DOCUMENTS for lang, _ in blocks(doc)
             if lang not in allowed and not lang.startswith("{")}
    assert not found


def test_ci_builds_the_docs_as_the_readme_says():
    ci = (REPO / ".ci" / "run").read_text()
    readme = "\n".join(code for lang, code in blocks(REPO / "README.md") if lang == "bash")
    build = next(line for line in readme.splitlines() if line.startswith("sphinx-build"))
    assert build in NOT_RUN and "-W" in build and " -n " in build
    assert re.search(r"sphinx-build -W --keep-going -n (-q )?-b html docs \S+", ci)


def test_outputs_have_their_own_names():
    """issue 27 item 2: following a page in order, no step writes over an earlier step's
    output (each --out/--json/--markdown/--summary names a new file, ``--force`` aside)."""
    for document in DOCUMENTS:
        seen: dict[str, str] = {}
        for lang, code in blocks(document):
            if lang != "bash":
                continue
            for line in code.splitlines():
                if "--force" in line:
                    continue
                for name in re.findall(r"--(?:out|json|markdown|summary) (\S+)", line):
                    assert name not in seen, f"{document.name}: {name} written twice"
                    seen[name] = line
