"""Every docstring example of the package runs (numpy-doc ``Examples`` sections).

The modules are found by reading the source for ``>>>``, so a new example is
tested without being listed anywhere.
"""

from __future__ import annotations

import doctest
import importlib

import pytest

from tests.conftest import REPO
from tests.test_layering import modules

#: Modules whose examples a test of their own runs (they drive an env: ~10 s each).
RUN_ELSEWHERE = {"sandbox.episodes.policies": "tests/episodes/test_policies.py",
                 "sandbox.episodes.rollout": "tests/episodes/test_rollout.py",
                 "sandbox.episodes.scenarios": "tests/episodes/test_scenarios.py"}
WITH_EXAMPLES = sorted(name for name, path in modules().items()
                       if ">>>" in path.read_text(encoding="utf-8") and name not in RUN_ELSEWHERE)


@pytest.mark.parametrize("name", sorted(RUN_ELSEWHERE))
def test_the_other_examples_run_elsewhere(name):
    assert f"doctest.testmod({name}" in (REPO / RUN_ELSEWHERE[name]).read_text(encoding="utf-8")


def test_examples_are_found():
    assert {"sandbox.core.model", "sandbox.core.predictor", "sandbox.data.filtering",
            "sandbox.robot.kinematics"} <= set(WITH_EXAMPLES)


@pytest.mark.parametrize("name", WITH_EXAMPLES)
def test_docstring_examples(name):
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0
