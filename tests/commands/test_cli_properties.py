"""Property tests of the command line's numeric options: any text is parsed to a finite value
inside the option's range, or refused by argparse naming the option (issue 13, item 6)."""

from __future__ import annotations

import argparse
import math
import os

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from sandbox.cli import build_parser

#: Examples per property test; raise ``SANDBOX_FUZZ_EXAMPLES`` for a longer campaign.
EXAMPLES = int(os.environ.get("SANDBOX_FUZZ_EXAMPLES", "80"))


def _numeric_options() -> list[tuple[list[str], str, argparse.Action]]:
    """(command words, option string, action) of every option whose type is not str."""
    out = []

    def walk(parser, words):
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, child in action.choices.items():
                    walk(child, [*words, name])
            elif action.option_strings and action.type not in (None, str) \
                    and action.nargs is None:
                out.append((words, action.option_strings[-1], action))
    walk(build_parser(), [])
    return out


OPTIONS = _numeric_options()
NUMERIC = [o for o in OPTIONS if "file" not in getattr(o[2].type, "__name__", "")
           and "folder" not in getattr(o[2].type, "__name__", "")]
TEXT = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(min_value=-10**30, max_value=10**30).map(str),
    st.sampled_from(["nan", "inf", "-inf", "1e309", "", " ", "0x10", "1,2", "1e-400", "½",
                     "3.", ".5", "+7", "1_000", "None", "true"]),
    st.text(alphabet="0123456789.,-+e nai", max_size=12),
)


def test_the_walk_finds_the_numeric_options():
    names = {(tuple(w), o) for w, o, _ in NUMERIC}
    assert (("evaluate",), "--workers") in names and (("fit",), "--n-basis") in names
    assert len(NUMERIC) >= 20


@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(pick=st.sampled_from(NUMERIC), text=TEXT)
def test_numeric_option_text_parses_in_range_or_is_refused(pick, text):
    words, option, action = pick
    try:
        value = action.type(text)
    except argparse.ArgumentTypeError as error:
        assert "expected" in str(error)
        return
    except Exception as error:  # anything else would reach argparse as a bare "invalid"
        pytest.fail(f"{' '.join(words)} {option} {text!r}: {type(error).__name__}: {error}")
    values = value if isinstance(value, tuple) else (value,)
    assert values and all(isinstance(v, int | float) and math.isfinite(v) for v in values)
