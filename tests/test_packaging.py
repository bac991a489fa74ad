"""Every package directory ships: a regular (non-editable) install must not lose one."""

import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


@pytest.mark.skipif(sys.version_info < (3, 11), reason="tomllib needs Python 3.11")
def test_every_package_is_listed_in_pyproject():
    import tomllib

    config = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]
    listed = set(config["packages"])
    mapped = {name: REPO / path for name, path in config["package-dir"].items()}
    found = set()
    for root_name, root in mapped.items():
        for init in root.rglob("__init__.py"):
            rel = init.parent.relative_to(root)
            found.add(".".join([root_name, *rel.parts]))
    # Data-only folders (no __init__.py) ship as packages of their files, so that setuptools
    # does not warn that they would be ignored (its "Package would be ignored" warning).
    data = {name for name, files in config["package-data"].items() if name not in found}
    for name in data:
        folder = mapped["sandbox"].joinpath(*name.split(".")[1:])
        assert folder.is_dir() and not (folder / "__init__.py").exists(), name
        assert any(any(folder.glob(pattern)) for pattern in config["package-data"][name]), name
    assert found - listed == set(), "package directories missing from pyproject.toml"
    assert listed - found - data == set(), "pyproject.toml lists packages that do not exist"


@pytest.mark.skipif(sys.version_info < (3, 11), reason="tomllib needs Python 3.11")
def test_one_version_source_and_the_typing_marker_ships():
    import tomllib

    import sandbox

    config = tomllib.loads((REPO / "pyproject.toml").read_text())
    assert "version" not in config["project"] and "version" in config["project"]["dynamic"]
    attr = config["tool"]["setuptools"]["dynamic"]["version"]["attr"]
    assert attr == "sandbox.__version__" and sandbox.__version__.count(".") == 2
    assert (REPO / "sandbox" / "py.typed").is_file()
    assert "py.typed" in config["tool"]["setuptools"]["package-data"]["sandbox"]
    assert "Typing :: Typed" in config["project"]["classifiers"]
    assert config["project"]["urls"]


def test_ci_runs_the_gates_before_the_readme_test_command():
    lines = (REPO / ".ci" / "run").read_text().splitlines()
    commands = [line.strip() for line in lines if line.strip() and not line.startswith("#")]
    assert commands.index("ruff check sandbox envs tests") < len(commands) - 1
    assert commands.index("mypy") < len(commands) - 1


def test_changelog_names_the_current_version():
    import sandbox

    assert f"## {sandbox.__version__}" in (REPO / "CHANGELOG.md").read_text()


def _lower_bounds(requirements: list[str]) -> dict[str, str]:
    """``{"numpy": "1.24", ...}``: each requirement's ``>=`` bound (markers ignored)."""
    import re

    out = {}
    for req in requirements:
        found = re.match(r"^([A-Za-z0-9_.\-]+)(?:\[[^\]]*\])?\s*>=\s*([0-9.]+)", req)
        if found:
            out[found[1].lower()] = found[2]
    return out


def _pins(path: Path) -> dict[str, str]:
    pins = {}
    for line in path.read_text().splitlines():
        line = line.split("#")[0].strip()
        if line:
            name, version = line.split("==")
            pins[name.strip().lower()] = version.strip()
    return pins


def _same_version(bound: str, pin: str) -> bool:
    """``6`` and ``6.0.0`` name the same release."""
    def parts(v):
        p = [int(x) for x in v.split(".")]
        while p and p[-1] == 0:
            p.pop()
        return p
    return parts(bound) == parts(pin)


@pytest.mark.skipif(sys.version_info < (3, 11), reason="tomllib needs Python 3.11")
def test_the_lowest_versions_ci_tests_are_the_declared_ones():
    """issue 26 item 6: .ci/lowest installs .ci/lowest-constraints.txt; each pin there is a
    declared lower bound (runtime, test and dask), and every declared bound is pinned."""
    import tomllib

    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    extras = project["optional-dependencies"]
    declared = _lower_bounds(project["dependencies"] + extras["test"] + extras["dask"])
    declared.pop("ruff"), declared.pop("mypy")     # the gates, not the suite
    pins = _pins(REPO / ".ci" / "lowest-constraints.txt")
    assert declared.keys() <= pins.keys(), sorted(declared.keys() - pins.keys())
    for name, bound in declared.items():
        assert _same_version(bound, pins[name]), (name, bound, pins[name])
    script = (REPO / ".ci" / "lowest").read_text()
    assert "-c .ci/lowest-constraints.txt" in script and "python -m pytest" in script


def test_the_citation_names_this_version_and_the_paper():
    """CITATION.cff (validated against the CFF schema by cffconvert in .ci/run) cites the
    software at the version of sandbox/__init__.py, and the paper it implements."""
    import yaml

    import sandbox

    citation = yaml.safe_load((REPO / "CITATION.cff").read_text())
    assert citation["cff-version"] == "1.2.0" and citation["type"] == "software"
    assert citation["version"] == sandbox.__version__
    assert citation["license"] == "BSD-3-Clause"
    paper = citation["preferred-citation"]
    assert paper["title"] == "Dynamic Interaction Probabilistic Movement Primitives"
    assert "1809.04215" in paper["url"]


@pytest.mark.skipif(sys.version_info < (3, 11), reason="tomllib needs Python 3.11")
def test_the_license_is_an_spdx_expression_without_a_classifier():
    """setuptools >= 77 deprecates a license table and license classifiers (deadline
    February 2027): the license is an SPDX expression, its file in license-files."""
    import tomllib

    config = tomllib.loads((REPO / "pyproject.toml").read_text())
    project = config["project"]
    assert project["license"] == "BSD-3-Clause" and project["license-files"] == ["LICENSE"]
    assert not [c for c in project["classifiers"] if c.startswith("License ::")]
    assert any(r.startswith("setuptools>=77") for r in config["build-system"]["requires"])
    assert "docs" in project["optional-dependencies"]
