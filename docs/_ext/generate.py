"""Pages written at build time, never by hand (a Sphinx extension of this project).

- ``_generated/api/``: one page per public module of :mod:`sandbox` (``automodule`` of
  every module whose dotted name has no part starting with ``_``), and an index;
- ``_generated/cli.md``: the ``--help`` of every command, from :func:`sandbox.cli.build_parser`;
- ``_generated/environments/``: one page per registered environment id, Gymnasium style:
  the spaces read off a made environment, the rest from the environment's docstring;
- ``_generated/results.md``: ``notebooks/figures/results.md`` and its figures, as written by
  ``python -m sandbox results --data ... --out notebooks/figures --force``.

A reference to a public alias (``sandbox.core.DynamicPredictor``, defined in
``sandbox.core.predictor``) resolves to the definition's entry.
"""

from __future__ import annotations

import argparse
import importlib
import inspect
import os
import pkgutil
import re
import shutil
from pathlib import Path

DOCS = Path(__file__).resolve().parents[1]
REPO = DOCS.parent
OUT = DOCS / "_generated"
FIGURES = REPO / "notebooks" / "figures"
PACKAGES = ("sandbox", "sandbox.envs", "sandbox.urdf")


def public_modules() -> list[str]:
    """Dotted names of every public module and package of the project, sorted."""
    names = set()
    for root in PACKAGES:
        package = importlib.import_module(root)
        names.add(root)
        for info in pkgutil.walk_packages(package.__path__, root + "."):
            if any(part.startswith("_") for part in info.name.split(".")):
                continue
            names.add(info.name)
    return sorted(names)


def _write(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.is_file() or path.read_text() != text:  # unchanged pages are not rebuilt
        path.write_text(text)


def write_api() -> None:
    modules = public_modules()
    lines = ["API reference", "=============", "",
             "Every public module, generated from the docstrings (numpydoc). The names most",
             "users need: :class:`sandbox.core.IProMP` (fit, save, load),",
             ":class:`sandbox.core.DynamicPredictor` and :class:`sandbox.core.StaticPredictor`",
             "(predict online), :func:`sandbox.data.synthetic.make_dataset`,",
             ":func:`sandbox.data.load_dataset`, :class:`sandbox.envs.BaxterHandoverEnv` and",
             ":class:`sandbox.episodes.policies.IProMPPolicy`.", "",
             ".. toctree::", "   :maxdepth: 1", ""]
    lines += [f"   {name}" for name in modules]
    _write(OUT / "api" / "index.rst", "\n".join(lines) + "\n")
    for stale in (OUT / "api").glob("sandbox*.rst"):  # a module renamed or removed since
        if stale.stem not in modules:
            stale.unlink()
    for name in modules:
        title = f"``{name}``"
        _write(OUT / "api" / f"{name}.rst",
               f"{title}\n{'=' * len(title)}\n\n.. automodule:: {name}\n")


def _subcommands(parser: argparse.ArgumentParser):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            yield from action.choices.items()


def _cli_sections(parser: argparse.ArgumentParser, prefix: str, level: int) -> list[str]:
    out = []
    for name, child in _subcommands(parser):
        prog = f"{prefix} {name}"
        out += [f"{'#' * level} `{prog}`", "", (child.description or "").strip(), "",
                "```text", child.format_help().rstrip(), "```", ""]
        out += _cli_sections(child, prog, level + 1)
    return out


def write_cli() -> None:
    from sandbox.cli import build_parser

    columns = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = "100"  # argparse wraps to the terminal: a fixed width here
    try:
        parser = build_parser()
        lines = ["# Command-line reference", "",
                 "Generated from the argument parsers (`sandbox.cli.build_parser`): what",
                 "`python -m sandbox COMMAND --help` prints. The same commands run as",
                 "`handover-sandbox COMMAND` once the package is installed.", "",
                 "```text", parser.format_help().rstrip(), "```", ""]
        lines += _cli_sections(parser, "python -m sandbox", 2)
    finally:
        if columns is None:
            os.environ.pop("COLUMNS", None)
        else:
            os.environ["COLUMNS"] = columns
    _write(OUT / "cli.md", "\n".join(lines))


def _docstring_sections(obj) -> dict[str, str]:
    """The numpydoc sections (title -> body) of an object's docstring."""
    lines = inspect.cleandoc(obj.__doc__ or "").splitlines()
    sections, title, body = {}, "", []
    for i, line in enumerate(lines):
        nxt = lines[i + 1] if i + 1 < len(lines) else ""
        if line.strip() and re.fullmatch(r"-{3,}", nxt.strip()) and len(nxt.strip()) == len(
                line.strip()):
            sections[title] = "\n".join(body).strip()
            title, body = line.strip(), []
        elif not re.fullmatch(r"-{3,}", line.strip()):
            body.append(line)
    sections[title] = "\n".join(body).strip()
    return sections


def _bounds(space) -> str:
    import numpy as np

    if not hasattr(space, "low"):  # MultiBinary flags
        return "{0, 1}" if type(space).__name__ == "MultiBinary" else type(space).__name__
    low, high = np.min(space.low), np.max(space.high)
    return f"[{low:.4g}, {high:.4g}]" if np.all(np.isfinite([low, high])) else "(-inf, inf)"


def _space_table(space) -> list[str]:
    rows = [".. list-table::", "   :header-rows: 1", "", "   * - key", "     - shape",
            "     - dtype", "     - bounds"]
    for key, sub in space.spaces.items():
        rows += [f"   * - ``{key}``", f"     - {sub.shape}", f"     - {sub.dtype}",
                 f"     - {_bounds(sub)}"]
    return rows + [""]


def _env_page(env_id: str) -> str:
    import gymnasium as gym

    from sandbox.envs.handover import BaxterHandoverEnv
    from sandbox.robot.facts import ARM_JOINTS as LEFT_ARM_JOINTS

    spec = gym.spec(env_id)
    env = gym.make(env_id)
    try:
        obs_space, act_space = env.observation_space, env.action_space
    finally:
        env.close()
    doc = _docstring_sections(BaxterHandoverEnv)
    title = f"``{env_id}``"
    kwargs = ", ".join(f"{k}={v!r}" for k, v in spec.kwargs.items())
    out = [title, "=" * len(title), "",
           ".. list-table::", "   :stub-columns: 1", "",
           "   * - Action space", f"     - ``Box({act_space.shape[0]},)`` {act_space.dtype}",
           "   * - Observation space", f"     - ``Dict`` of {len(obs_space.spaces)} entries",
           "   * - Import", f"     - ``import sandbox.envs; gym.make(\"{env_id}\")``",
           "   * - Entry point", f"     - ``{spec.entry_point}`` ({kwargs})",
           "   * - Episode length", f"     - ``max_episode_steps={spec.max_episode_steps}``",
           "   * - Vector entry point", f"     - ``{spec.vector_entry_point}``", "",
           "Generated from the registered environment (the spaces are read off ``gym.make``)",
           "and from the docstring of :class:`sandbox.envs.handover.BaxterHandoverEnv`.", "",
           "Description", "-----------", "", doc.get("Description", ""), "",
           "Action space", "------------", "",
           ".. list-table::", "   :header-rows: 1", "", "   * - index", "     - meaning",
           "     - bounds"]
    names = [*LEFT_ARM_JOINTS, "gripper command (> 0 closes)"]
    for i, name in enumerate(names):
        unit = "" if i == len(names) - 1 else " (rad)"
        out += [f"   * - {i}", f"     - ``{name}``{unit}" if unit else f"     - {name}",
                f"     - [{act_space.low[i]:.4g}, {act_space.high[i]:.4g}]"]
    out += ["", "Observation space", "-----------------", "", *_space_table(obs_space),
            "What each entry means:", "", doc.get("Observation space", ""), ""]
    for section in ("Rewards", "Starting state", "Episode end", "Arguments", "Rendering",
                    "Version history"):
        out += [section, "-" * len(section), "", doc.get(section, ""), ""]
    return "\n".join(out)


def write_environments() -> None:
    import sandbox.envs

    ids = [*sandbox.envs.ENV_IDS, *sandbox.envs.LEGACY_IDS, *sandbox.envs.ROBOT_IDS]
    lines = ["Environments", "============", "",
             "One page per registered id (``import sandbox.envs`` registers them). The",
             "``-v0`` ids keep v0's observation (no ``arm``, ``emg``) for one release. The",
             "``-v2`` ids take any arm (``robot=``, :doc:`/tutorials/robots`); shown with Baxter.",
             "How to use them: :doc:`/tutorials/environments`.", "",
             ".. toctree::", "   :maxdepth: 1", ""]
    for env_id in ids:
        page = env_id.replace("/", "-")
        lines.append(f"   {page}")
        _write(OUT / "environments" / f"{page}.rst", _env_page(env_id))
    _write(OUT / "environments" / "index.rst", "\n".join(lines) + "\n")


def _shift_headings(text: str) -> str:
    """``####`` -> ``###`` and ``###`` -> ``##``: results.md's levels under a page title."""
    return re.sub(r"^(#{3,6}) ", lambda m: "#" * (len(m.group(1)) - 1) + " ", text, flags=re.M)


def write_results() -> None:
    source = FIGURES / "results.md"
    text = source.read_text()
    target = OUT / "results"
    for figure in FIGURES.rglob("*.png"):
        dest = target / figure.relative_to(FIGURES)
        dest.parent.mkdir(parents=True, exist_ok=True)
        if not dest.is_file() or dest.read_bytes() != figure.read_bytes():
            shutil.copyfile(figure, dest)
    text = text.replace("](notebooks/figures/", "](results/")
    _write(OUT / "results.md", _shift_headings(text))


def write_equations() -> None:
    """Each of the paper's equations, its number, what it states and the code implementing
    it (:data:`sandbox.core.EQUATIONS`); a private function is named, not linked."""
    from equations import LATEX

    from sandbox.core import EQUATIONS

    if sorted(LATEX) != sorted(EQUATIONS):
        raise ValueError(f"docs/_ext/equations.py has equations {sorted(LATEX)}, "
                         f"sandbox.core.EQUATIONS {sorted(EQUATIONS)}")
    lines = []
    for number, (statement, functions) in sorted(EQUATIONS.items()):
        links = [f"`{f}`" if any(p.startswith("_") for p in f.split(".")) else
                 f"{{py:obj}}`~{f}`" for f in functions]
        modules = sorted({f.rsplit(".", 2)[0] if f.split(".")[-2][:1].isupper() else
                          f.rsplit(".", 1)[0] for f in functions})
        lines += ["$$", LATEX[number], f"$$ ({number})", "",
                  f"**Eq. {number}**: {statement}. Implemented by {', '.join(links)} "
                  f"(in {', '.join(f'`{m}`' for m in modules)}).", ""]
    _write(OUT / "equations.md", "\n".join(lines))


def generate(app=None, config=None) -> None:
    write_equations()
    write_api()
    write_cli()
    write_environments()
    write_results()


def _definitions(target: str) -> list[str]:
    """Where ``target`` (``package.Name[.member]``, through a re-export) may be defined."""
    import sys

    parts = target.split(".")
    for cut in range(len(parts) - 1, 0, -1):  # the longest importable module prefix
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
            break
        except ImportError:
            continue
    else:
        return []
    rest = parts[cut:]
    holder, walked = obj, 0
    for name in rest:  # walk to the deepest class or function that exists
        member = getattr(holder, name, None)
        if not (hasattr(member, "__qualname__") and hasattr(member, "__module__")):
            break  # a property, an attribute or nothing: named under its class
        holder, walked = member, walked + 1
    qualname = getattr(holder, "__qualname__", None)
    if walked and qualname and str(getattr(holder, "__module__", "")).startswith("sandbox."):
        return [".".join([holder.__module__, qualname, *rest[walked:]])]
    if len(rest) == 1 and hasattr(obj, rest[0]):  # data: any public module holding it
        value = getattr(obj, rest[0])
        return [f"{name}.{rest[0]}" for name, module in sorted(sys.modules.items())
                if name.startswith("sandbox.") and getattr(module, rest[0], None) is value
                and not any(part.startswith("_") for part in name.split("."))]
    return []


def resolve_alias(app, env, node, contnode):
    """Resolve ``sandbox.x.Name`` re-exported from ``sandbox.x.module`` to its definition."""
    target = node.get("reftarget", "")
    if node.get("refdomain") != "py" or not target.startswith("sandbox."):
        return None
    for real in _definitions(target):
        if real == target:
            continue
        found = node.deepcopy()
        found["reftarget"] = real
        resolved = env.get_domain("py").resolve_xref(env, node.get("refdoc"), app.builder,
                                                     node["reftype"], real, found, contnode)
        if resolved is not None:
            return resolved
    return None


def setup(app):
    app.connect("config-inited", generate)
    app.connect("missing-reference", resolve_alias)
    return {"parallel_read_safe": True, "version": "1"}
