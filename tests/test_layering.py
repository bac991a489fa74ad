"""The import graph, read with ``ast``: no cycle, and no arrow the layering forbids.

The layering (DESIGN.md section 2 and issue 16; the README's developer section
draws it): ``sandbox/validation.py`` (the ``check_*`` validators and the
JSON/YAML reader) is neutral: every part may import it and it imports nothing
of the project; the core imports only numpy, scipy and itself; the robot package
nothing of the project; data may use the core and the robot (the synthetic
generator solves Baxter's IK); the viewer draws the robot; the environments are
sim + robot + human (data) and may render with the viewer, and reach the core
only through a policy; the evaluation runs the core on data; the policies-and-
episodes layer (``sandbox/episodes/``: policies, the rollout loop, scenarios,
scenario files, recording, the keyboard teleop) joins policies and environments;
benchmarks may use all of that; the commands everything.

Every import counts, also one inside a function (a late import still ties the
modules together); only imports under ``if TYPE_CHECKING:`` are left out (they
never run). Today's known breaks are listed in :data:`KNOWN` with the item of
issue 16 that removes them; an entry no longer needed fails
:func:`test_known_breaks_are_still_needed`, so the list only shrinks.
"""

from __future__ import annotations

import ast
import functools
import sys
from collections.abc import Iterator
from pathlib import Path

from tests.conftest import REPO

EPISODES = {"episodes"}
COMMANDS = {"commands", "cli", "__main__"}
#: Parts each part may import (besides itself and the neutral root package).
ALLOWED = {
    "limits": set(),                    # neutral: sandbox/limits.py, the one table of limits
    "validation": {"limits"},           # neutral: sandbox/validation.py, used by every part
    "core": set(),
    "methods": {"core"},                # other methods behind the predictor interface
    "robot": set(),
    "data": {"core", "robot"},
    "viz": {"robot"},
    "envs": {"robot", "data", "viz"},
    "eval": {"core", "methods", "data", "robot"},
    "episodes": {"core", "methods", "data", "robot", "envs", "viz"},
    "bench": {"core", "methods", "data", "robot", "envs", "viz", "eval", "episodes"},
    "commands": {"core", "methods", "data", "robot", "envs", "viz", "eval", "episodes",
                 "bench"},
}
for _part, _allowed in ALLOWED.items():
    if _part not in ("validation", "limits"):
        _allowed.update(("validation", "limits"))
#: Known breaks: (importing part, imported module or package) -> the change that removes it.
KNOWN = {
}
#: Known cycles (sets of modules) -> the change that removes them (none left).
KNOWN_CYCLES: dict[frozenset[str], str] = {}


def modules() -> dict[str, Path]:
    """Every module of the package by dotted name (``envs/`` installs as ``sandbox.envs``)."""
    out = {}
    for folder, package in ((REPO / "sandbox", "sandbox"), (REPO / "envs", "sandbox.envs")):
        for path in sorted(folder.rglob("*.py")):
            parts = [p for p in path.relative_to(folder).with_suffix("").parts
                     if p != "__init__"]
            out[".".join([package, *parts])] = path
    return out


def _runtime_nodes(tree: ast.AST) -> Iterator[ast.AST]:
    """All nodes except the bodies of ``if TYPE_CHECKING:`` blocks."""
    stack = [tree]
    while stack:
        node = stack.pop()
        yield node
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and "TYPE_CHECKING" in ast.unparse(child.test):
                stack.extend(child.orelse)
            else:
                stack.append(child)


def imports(name: str, path: Path, known: dict[str, Path]) -> set[str]:
    """Project modules ``name`` imports (``from P import m`` of a submodule m: P.m)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out = set()
    for node in _runtime_nodes(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                up = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(up + ([base] if base else []))
            subs = {f"{base}.{a.name}" for a in node.names} & set(known)
            out.update(subs or {base})
    return {m for m in out if m == "sandbox" or m.startswith("sandbox.")}


@functools.cache
def _graph() -> dict[str, frozenset[str]]:
    known = modules()
    return {name: frozenset(imports(name, path, known) & set(known))
            for name, path in known.items()}


def graph() -> dict[str, set[str]]:
    """Module -> the project modules it imports (read once per session)."""
    return {name: set(targets) for name, targets in _graph().items()}


def part(module: str) -> str:
    names = module.split(".")
    top = names[1] if len(names) > 1 else ""
    if top in EPISODES:
        return "episodes"
    if top in COMMANDS:
        return "commands"
    if top in ("", "urdf"):
        return "root"                    # the package itself and the URDF data files
    return top


def breaks() -> dict[tuple[str, str], list[str]]:
    """Arrows the layering forbids: (part, imported module) -> importing modules."""
    out: dict[tuple[str, str], list[str]] = {}
    for a, targets in graph().items():
        for b in targets:
            pa, pb = part(a), part(b)
            if pb not in (pa, "root") and pb not in ALLOWED[pa]:
                out.setdefault((pa, b), []).append(a)
    return out


def _known(key: tuple[str, str]) -> tuple[str, str] | None:
    pa, b = key
    for kp, km in KNOWN:
        if kp == pa and (b == km or b.startswith(km + ".")):
            return (kp, km)
    return None


def cycles(g: dict[str, set[str]]) -> list[frozenset[str]]:
    """Strongly connected components of more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out = []
    for root in g:
        if root in index:
            continue
        work = [(root, iter(sorted(g[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(g[w]))))
                elif w in on:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = set()
                while True:
                    w = stack.pop()
                    on.discard(w)
                    comp.add(w)
                    if w == v:
                        break
                if len(comp) > 1:
                    out.append(frozenset(comp))
    return out


def test_the_graph_is_read():
    g = graph()
    assert "sandbox.core.predictor" in g and "sandbox.envs.handover" in g
    assert "sandbox.core.plan" in g["sandbox.core.updating"]   # the predictors' machinery
    assert "sandbox.core.io" in g["sandbox.core.model"]


def test_no_import_cycle():
    found = {c: KNOWN_CYCLES.get(c) for c in cycles(graph())}
    new = [sorted(c) for c, why in found.items() if why is None]
    assert not new, f"import cycles: {new}"


def test_io_and_model_do_not_import_each_other():
    g = graph()
    assert "sandbox.core.model" not in g["sandbox.core.io"]


def test_no_import_breaks_the_layering():
    new = {key: mods for key, mods in breaks().items() if _known(key) is None}
    assert not new, f"imports the layering forbids (part, module): importers {new}"


def test_known_breaks_are_still_needed():
    used = {_known(key) for key in breaks()}
    stale = [k for k in KNOWN if k not in used]
    stale_cycles = [sorted(c) for c in KNOWN_CYCLES if c not in set(cycles(graph()))]
    assert not stale and not stale_cycles, (
        f"fixed, so remove from KNOWN / KNOWN_CYCLES: {stale} {stale_cycles}")


#: Optional packages a core module may import inside a function, when installed (the
#: import is guarded: without the package the module takes its numpy path).
OPTIONAL_IN_CORE = {"sandbox.core._kernels": {"numba"}}


def test_core_imports_only_numpy_scipy_and_the_standard_library():
    bad = {}
    for name, path in modules().items():
        if part(name) != "core":
            continue
        allowed = (set(sys.stdlib_module_names) | {"numpy", "scipy", "sandbox"}
                   | OPTIONAL_IN_CORE.get(name, set()))
        for node in _runtime_nodes(ast.parse(path.read_text(encoding="utf-8"))):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom)
                     and not node.level else [])
            for n in names:
                if n.split(".")[0] not in allowed or (
                        n.startswith("sandbox") and part(n) not in ("core", "root", "validation",
                                                                "limits")):
                    bad.setdefault(name, []).append(n)
        tree = ast.parse(path.read_text(encoding="utf-8"))
        top = {a.name.split(".")[0] for node in tree.body if isinstance(node, ast.Import)
               for a in node.names}
        if top & OPTIONAL_IN_CORE.get(name, set()):           # optional: imported late only
            bad.setdefault(name, []).extend(sorted(top & OPTIONAL_IN_CORE[name]))
    assert not bad, bad


def test_the_neutral_module_loads_only_numpy_and_the_standard_library():
    """What every part imports may not pull a heavy or project import in at load time
    (PyYAML is imported inside ``read_mapping``, when a file is read)."""
    tree = ast.parse((REPO / "sandbox" / "validation.py").read_text(encoding="utf-8"))
    loaded = [a.name for node in tree.body if isinstance(node, ast.Import) for a in node.names]
    loaded += [node.module or "" for node in tree.body if isinstance(node, ast.ImportFrom)]
    allowed = set(sys.stdlib_module_names) | {"numpy", "__future__"}
    assert loaded and all(n.split(".")[0] in allowed for n in loaded), loaded


def test_the_table_of_limits_loads_only_the_standard_library():
    """``sandbox/limits.py`` is read while ``--help`` is built and by every part."""
    tree = ast.parse((REPO / "sandbox" / "limits.py").read_text(encoding="utf-8"))
    loaded = [a.name for node in ast.walk(tree) if isinstance(node, ast.Import)
              for a in node.names]
    loaded += [node.module or "" for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)]
    allowed = set(sys.stdlib_module_names) | {"__future__"}
    assert loaded and all(n.split(".")[0] in allowed for n in loaded), loaded


def test_cycle_finder_finds_a_cycle():
    g = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert cycles(g) == [frozenset({"a", "b", "c"})]
