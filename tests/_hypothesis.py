"""Shared hypothesis settings of the property suites (issue 26).

The suites run in CI with a bounded, derandomised number of examples (the same
inputs every run: a red CI is reproducible). ``SANDBOX_FUZZ_EXAMPLES=N`` (or
``SANDBOX_HYPOTHESIS_EXAMPLES=N``) runs every property test with N random
examples instead, for a longer campaign::

    SANDBOX_FUZZ_EXAMPLES=2000 python -m pytest tests -k "propert or hypothesis"
"""

from __future__ import annotations

import os

from hypothesis import HealthCheck, settings


def _campaign() -> int:
    for name in ("SANDBOX_FUZZ_EXAMPLES", "SANDBOX_HYPOTHESIS_EXAMPLES"):
        text = os.environ.get(name, "").strip()
        if text:
            return int(text)
    return 0


#: Examples of a campaign (0: none set, the suites' own bounded numbers).
CAMPAIGN = _campaign()


def examples(n: int) -> int:
    """``n`` examples in the suite, or the campaign's number."""
    return CAMPAIGN or n


def property_settings(n: int) -> settings:
    """Settings of a property test with ``n`` examples by default (see module docstring)."""
    return settings(max_examples=examples(n), deadline=None, derandomize=not CAMPAIGN,
                    database=None, suppress_health_check=[HealthCheck.too_slow,
                                                          HealthCheck.data_too_large,
                                                          HealthCheck.function_scoped_fixture])
