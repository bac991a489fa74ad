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
