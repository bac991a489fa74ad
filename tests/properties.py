"""Shared parts of the property-based (hypothesis) tests of the files a user writes.

Issue 26 item 1 / issue 29: spec files, scenario and sweep YAML and settings
files are generated (valid documents with one value changed, arbitrary nested
documents, arbitrary text and bytes), read by the project's own reader, and
every outcome must be either an accepted value within the one table of limits
or one ``ValueError`` of one line that names the file and no internal
(``__init__``, ``codec``, ``RecursionError``, ``Traceback``); the folder the
file lies in is left as it was.

The number of examples per test is small in CI (:data:`EXAMPLES`, 25); set
``SANDBOX_HYPOTHESIS_EXAMPLES`` (e.g. 2000) for a longer campaign.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

import yaml
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st

#: Examples per property test (``SANDBOX_HYPOTHESIS_EXAMPLES``, default 25).
EXAMPLES = int(os.environ.get("SANDBOX_HYPOTHESIS_EXAMPLES", "25"))
#: Hypothesis settings of these tests: bounded, no deadline (a loaded 2-core machine).
SETTINGS = settings(max_examples=EXAMPLES, deadline=None, derandomize=False,
                    suppress_health_check=[HealthCheck.too_slow,
                                           HealthCheck.function_scoped_fixture,
                                           HealthCheck.data_too_large])
#: Words of a message that name internals rather than the user's input.
INTERNALS = ("__init__", "codec", "RecursionError", "Traceback", "unexpected keyword",
             "positional argument", "object has no attribute", "NoneType", "please report")

WORDS = ("hand", "arm", "emg", "joint", "marginal", "all", "latest", "dynamic", "static", "up",
         "right", "diverging", "objects", "1e-3", "1e2", "nan", "inf", "-inf", "null", "yes",
         "position", "signal", "t", "left_s0", "")
SCALARS = st.one_of(
    st.none(), st.booleans(),
    st.integers(-3, 200), st.integers(-(10**6), 10**6), st.integers(),
    st.integers(10**18, 10**30),
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(-5, 5), st.floats(0, 1), st.sampled_from([1e-300, 1e300, -0.0, 5e-324]),
    st.text(max_size=12), st.sampled_from(WORDS),
)


def documents(keys: tuple[str, ...]) -> st.SearchStrategy[Any]:
    """Arbitrary nested documents whose mapping keys are mostly ``keys``."""
    names = st.one_of(st.sampled_from(keys), st.text(max_size=8)) if keys else st.text(max_size=8)
    return st.recursive(SCALARS, lambda inner: st.one_of(
        st.lists(inner, max_size=4), st.dictionaries(names, inner, max_size=4)), max_leaves=16)


def mutated(base: dict, keys: tuple[str, ...]) -> st.SearchStrategy[dict]:
    """``base`` with one key (of ``keys`` or any) set to an arbitrary value, or removed."""
    value = documents(keys)

    @st.composite
    def build(draw):
        doc = json.loads(json.dumps(base))
        key = draw(st.one_of(st.sampled_from(keys), st.text(max_size=8)))
        if draw(st.booleans()) and key in doc:
            del doc[key]
        else:
            doc[key] = draw(value)
        return doc
    return build()


def write(path: Path, doc: Any) -> Path:
    """``doc`` as JSON (``.json``; NaN and infinities as Python writes them) or YAML."""
    if path.suffix == ".json":
        path.write_text(json.dumps(doc))
    else:
        path.write_text(yaml.safe_dump(doc, allow_unicode=True))
    return path


def snapshot(folder: Path) -> dict[str, bytes]:
    """Every file under ``folder`` (relative name -> bytes)."""
    return {str(p.relative_to(folder)): p.read_bytes()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def assert_clean_refusal(error: BaseException, path: Path) -> None:
    """``error`` is one ``ValueError`` of one line naming ``path`` and no internal."""
    assert type(error) is not AssertionError, error
    assert isinstance(error, ValueError), f"{type(error).__name__}: {error}"
    text = str(error)
    assert "\n" not in text and text.strip(), repr(text)
    assert str(path) in text, text
    assert not any(word in text for word in INTERNALS), text
    assert len(text) < 1000, text


def finite(value: Any) -> bool:
    """Whether ``value`` is a finite int or float (not a bool)."""
    return (isinstance(value, (int, float)) and not isinstance(value, bool)
            and math.isfinite(value))
