"""Shared fixtures.

Tests that need the recorded handovers or a browser use the fixtures below: on
a user's machine they skip when the resource is absent; under CI
(``SANDBOX_REQUIRE_DATA=1`` / ``SANDBOX_REQUIRE_BROWSER=1``) a missing resource
is a failure, not a skip.
"""

from __future__ import annotations

import os
import shutil
import signal
import tempfile
from pathlib import Path

import pytest

# Commands keep loaded trials in an on-disk cache (sandbox.data.cache): the tests
# (and the subprocesses they start) use a fresh one of their own, never the user's.
_CACHE = os.environ["SANDBOX_CACHE_DIR"] = tempfile.mkdtemp(prefix="sandbox-test-cache-")


def pytest_sessionfinish(session, exitstatus) -> None:
    shutil.rmtree(_CACHE, ignore_errors=True)


@pytest.hookimpl(trylast=True)    # after -k/-m have deselected: only what runs is ordered
def pytest_collection_modifyitems(config, items) -> None:
    """Order the tests so that no worker is left alone with a minute-long test at the end
    (session 11: the time of the test command). Only the order changes: every test runs,
    with the same fixtures.

    A module that holds a test marked ``slow`` is heavy. ``--dist worksteal`` (pyproject)
    first gives each of the n workers an equal run of this order, then an idle worker takes
    half of a busy one's unstarted tests, from the end of its run. So the heavy modules are
    dealt to the n runs, one each in turn, at the start of each run, and the light tests fill
    the runs up: every run ends with light tests, where the workers meet. In file order the
    docs' blocks, the notebooks and the browser came last. A module moves whole, so its
    module-scoped fixtures are still made once per worker that runs it. With ``-n 0`` (one
    run) the heavy modules simply go first.
    """
    lanes = max(1, int(getattr(config, "workerinput", {}).get("workercount", 1)))
    modules: dict[Path, list] = {}
    for item in items:
        modules.setdefault(item.path, []).append(item)
    heavy = [tests for tests in modules.values()
             if any(t.get_closest_marker("slow") for t in tests)]
    light = [t for tests in modules.values() if tests not in heavy for t in tests]
    ordered, left = [], len(items)
    for lane in range(lanes):
        size = left // (lanes - lane)     # worksteal's first share of the tests left
        run = [t for tests in heavy[lane::lanes] for t in tests]
        fill, light = light[:max(size - len(run), 0)], light[max(size - len(run), 0):]
        ordered += run + fill
        left -= len(run) + len(fill)
    items[:] = ordered + light


@pytest.fixture(autouse=True)
def _sigint_restored():
    """A test that runs ``sandbox.cli.run`` in-process leaves its "Ctrl-C ends the
    process" handler on SIGINT; put the previous one back, so no later test (in the same
    worker) starts with it."""
    previous = signal.getsignal(signal.SIGINT)
    yield
    if signal.getsignal(signal.SIGINT) is not previous and previous is not None:
        signal.signal(signal.SIGINT, previous)

REPO = Path(__file__).resolve().parents[1]
RECORDED_SET = "birl-handover-20180329"


def _require(flag: str) -> bool:
    return os.environ.get(flag, "") not in ("", "0", "false", "no")


def _missing(what: str, flag: str) -> None:
    if _require(flag):
        pytest.fail(f"{what} is required here ({flag}=1) but was not found")
    pytest.skip(f"{what} not found")


def recorded_root() -> Path:
    """Folder holding the shared recordings: ``$SANDBOX_DATA`` or ``../shared/data``.

    ``SANDBOX_DATA`` may name either the folder that holds ``birl-handover-20180329``
    or that set itself (issue 27 item 8: set to the set, the data tests used to skip
    silently); the set itself gives its parent.
    """
    env = os.environ.get("SANDBOX_DATA")
    if not env:
        return REPO.parent / "shared" / "data"
    path = Path(env)
    return path.parent if path.name == RECORDED_SET else path


@pytest.fixture(scope="session")
def recorded_dir() -> Path:
    """The recorded object-handover set (``<root>/birl-handover-20180329``)."""
    path = recorded_root() / RECORDED_SET
    if not path.is_dir():
        where = (f"SANDBOX_DATA={os.environ['SANDBOX_DATA']} is neither the set nor the "
                 "folder that holds it" if os.environ.get("SANDBOX_DATA") else
                 "set SANDBOX_DATA to the set or to the folder that holds it")
        _missing(f"the recorded handovers {RECORDED_SET} ({path}; {where})",
                 "SANDBOX_REQUIRE_DATA")
    return path


@pytest.fixture(scope="session")
def chromium() -> str:
    """Path of a Chromium executable for headless browser tests."""
    for name in ("chromium", "chromium-browser", "google-chrome"):
        exe = shutil.which(name)
        if exe:
            return exe
    _missing("a Chromium browser", "SANDBOX_REQUIRE_BROWSER")
    raise AssertionError("unreachable")
