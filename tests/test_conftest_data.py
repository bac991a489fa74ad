"""``SANDBOX_DATA`` names the recorded set or the folder that holds it (issue 27 item 8)."""

from pathlib import Path

import pytest

from tests import conftest


@pytest.mark.parametrize("given", ["parent", "set"])
def test_sandbox_data_accepts_the_set_or_its_parent(given, tmp_path, monkeypatch):
    recorded = tmp_path / conftest.RECORDED_SET
    recorded.mkdir()
    monkeypatch.setenv("SANDBOX_DATA", str(recorded if given == "set" else tmp_path))
    assert conftest.recorded_root() / conftest.RECORDED_SET == recorded


def test_a_wrong_sandbox_data_says_which_folder_is_expected(tmp_path, monkeypatch):
    monkeypatch.setenv("SANDBOX_DATA", str(tmp_path / "elsewhere"))
    monkeypatch.setenv("SANDBOX_REQUIRE_DATA", "1")
    with pytest.raises(pytest.fail.Exception, match="neither the set nor the folder"):
        conftest.recorded_dir.__wrapped__()


def test_the_default_is_the_shared_folder_beside_the_checkout(monkeypatch):
    monkeypatch.delenv("SANDBOX_DATA", raising=False)
    assert conftest.recorded_root() == Path(conftest.REPO).parent / "shared" / "data"
