"""The documentation's own checks (docs/_ext): they run inside the strict build in .ci/run;
here their logic is pinned. Needs the ``docs`` extra (.ci/run installs it)."""

import logging
import sys
from pathlib import Path

import pytest

pytest.importorskip("sphinx")
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs" / "_ext"))

import docscheck  # noqa: E402
import generate  # noqa: E402


def test_a_public_name_without_a_docstring_is_a_warning(caplog):
    with caplog.at_level(logging.WARNING):
        docscheck.check(None, "function", "sandbox.core.basis.f", None, {}, [])
        docscheck.check(None, "function", "sandbox.core.basis._private", None, {}, [])
        docscheck.check(None, "method", "sandbox.core.basis.Thing.g", None, {}, ["Does g."])
        docscheck.check(None, "data", "sandbox.core.basis.CONSTANT", None, {}, [])
    warned = [r.getMessage() for r in caplog.records]
    assert warned == ["public function sandbox.core.basis.f has no docstring"]


def test_a_reexported_name_resolves_to_its_definition():
    assert generate._definitions("sandbox.core.DynamicPredictor") == [
        "sandbox.core.predictor.DynamicPredictor"]
    assert generate._definitions("sandbox.core.IProMP.load") == ["sandbox.core.model.IProMP.load"]
    assert generate._definitions("sandbox.core.NoSuchName") == []


def test_every_public_module_gets_a_page_and_no_private_one():
    modules = generate.public_modules()
    assert {"sandbox.core.predictor", "sandbox.envs.handover", "sandbox.cli"} <= set(modules)
    assert not [m for m in modules if any(p.startswith("_") for p in m.split("."))]
