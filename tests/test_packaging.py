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
    assert found - listed == set(), "package directories missing from pyproject.toml"
    assert listed - found == set(), "pyproject.toml lists packages that do not exist"
