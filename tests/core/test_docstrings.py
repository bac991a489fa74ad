"""The examples in the core's docstrings run (numpy-doc ``Examples`` sections)."""

import doctest

import pytest

import sandbox.core.model
import sandbox.core.predictor


@pytest.mark.parametrize("module", [sandbox.core.model, sandbox.core.predictor])
def test_docstring_examples(module):
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0
