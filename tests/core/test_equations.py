"""The paper's equation numbers: one table (sandbox.core.EQUATIONS), cited consistently.

Every ``eq. N`` cited in the package, the README and the notebooks is an
equation of the table; every function of the table exists and carries a
``# eq. N`` comment beside the lines implementing N; and the table has as many
equations as the paper's LaTeX source numbers (when ``../shared/paper`` is there).
"""

from __future__ import annotations

import importlib
import inspect
import re
from pathlib import Path

import pytest

from sandbox.core import EQUATIONS
from tests.conftest import REPO, _missing

#: "eq. 3", "eqs. 16-18", "eq. 12, 15", "eq. 1 and 3", "eq. 1–4, 6".
_NUMBER = r"\d+(?:\s*[-–]\s*\d+)?"
CITATION = re.compile(rf"\beqs?\.\s*({_NUMBER}(?:\s*(?:,|and)\s*{_NUMBER})*)")
PAPER = REPO.parent / "shared" / "paper" / "dynamic-interaction-promps.tex"


def numbers(text: str) -> set[int]:
    """Equation numbers a citation list names ("16-18, 20" -> {16, 17, 18, 20})."""
    out: set[int] = set()
    for part in re.split(r",|and", text):
        ends = [int(x) for x in re.findall(r"\d+", part)]
        if ends:
            out.update(range(ends[0], ends[-1] + 1))
    return out


def cited(text: str) -> set[int]:
    return set().union(*(numbers(m.group(1)) for m in CITATION.finditer(text)))


def resolve(path: str):
    """The object a dotted path names (module, then attributes)."""
    parts = path.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ModuleNotFoundError:
            continue
        for name in parts[i:]:
            obj = getattr(obj, name)
        return obj
    raise ImportError(path)


def count_numbered(tex: str) -> int:
    """Numbered display equations of a LaTeX source, as LaTeX numbers them.

    ``equation``/``multline``: one number each (an ``aligned`` or ``array`` inside
    stays one). ``eqnarray``/``align``/``gather``/``flalign``: one per line
    (lines split at ``\\\\``, an empty last line not counted). Starred forms and
    lines or environments with ``\\nonumber``/``\\notag`` get none.
    """
    tex = re.sub(r"(?<!\\)%.*", "", tex)                       # comments
    tex = re.sub(r"\\newcommand\{[^}]*\}\{[^\n]*\}", "", tex)    # macro definitions
    tex = tex.replace("\\beq ", "\\begin{equation}").replace("\\eeq", "\\end{equation}")
    tex = tex.replace("\\bear ", "\\begin{eqnarray}").replace("\\eear", "\\end{eqnarray}")
    count = 0
    env = re.compile(r"\\begin\{(equation|multline|eqnarray|align|gather|flalign)\}(.*?)"
                     r"\\end\{\1\}", re.S)
    for kind, body in env.findall(tex):
        if kind in ("equation", "multline"):
            count += not re.search(r"\\(nonumber|notag)\b", body)
            continue
        lines = re.split(r"\\\\", body)
        if lines and not lines[-1].strip():
            lines = lines[:-1]
        count += sum(not re.search(r"\\(nonumber|notag)\b", line) for line in lines)
    return count


def test_table_numbers_the_equations_once_in_order():
    assert sorted(EQUATIONS) == list(range(1, len(EQUATIONS) + 1))
    for what, functions in EQUATIONS.values():
        assert what and functions


@pytest.mark.parametrize("n", sorted(EQUATIONS))
def test_every_function_of_the_table_exists(n):
    for path in EQUATIONS[n][1]:
        assert callable(resolve(path)), path


@pytest.mark.parametrize("n", sorted(EQUATIONS))
def test_each_equation_is_marked_beside_its_code(n):
    """At least one implementing function has a ``# eq. N`` comment naming N."""
    marked = []
    for path in EQUATIONS[n][1]:
        source = inspect.getsource(resolve(path))
        comments = "\n".join(re.findall(r"#[^\n]*", source))
        marked.append(n in cited(comments))
    assert any(marked), f"eq. {n}: no '# eq. {n}' comment in {EQUATIONS[n][1]}"


def _documents() -> list[Path]:
    files = sorted((REPO / "sandbox").rglob("*.py")) + sorted((REPO / "envs").rglob("*.py"))
    docs = sorted(p for p in (REPO / "docs").rglob("*.md") if "_build" not in p.parts)
    return files + [REPO / "README.md", *docs] + sorted((REPO / "notebooks").glob("*.ipynb"))


def test_every_citation_is_in_the_table():
    bad = {}
    total = 0
    for path in _documents():
        found = cited(path.read_text(encoding="utf-8"))
        total += len(found)
        unknown = found - set(EQUATIONS)
        if unknown:
            bad[str(path.relative_to(REPO))] = sorted(unknown)
    assert total > 20                # the citations were found at all
    assert not bad, f"equation numbers the paper does not have: {bad}"


@pytest.mark.parametrize("text, expected", [
    ("(eq. 16-18)", {16, 17, 18}), ("eq. 12, 15", {12, 15}), ("eq. 1 and 3", {1, 3}),
    ("(eq. 1–4, 6)", {1, 2, 3, 4, 6}), ("eqs. 8", {8}), ("frequency 3", set()),
])
def test_citations_are_parsed(text, expected):
    assert cited(text) == expected


def test_counting_numbered_environments():
    tex = (r"\begin{equation}a\end{equation} \begin{equation*}b\end{equation*}"
           r"\begin{align}c\\d\nonumber\\e\\\end{align} % \begin{equation}x\end{equation}" "\n"
           r"\begin{eqnarray}f\end{eqnarray} \[g\]")
    assert count_numbered(tex) == 4


def test_table_has_as_many_equations_as_the_paper():
    if not PAPER.is_file():
        _missing(f"the paper's source ({PAPER})", "SANDBOX_REQUIRE_DATA")
    assert count_numbered(PAPER.read_text(encoding="utf-8")) == len(EQUATIONS) == 20
