"""Property tests of settings files (``--config``): accepted within the table, or one line.

Issue 26 item 1 and issue 29 item 4: whatever a settings file holds, ``load``
returns options each within its entry of :data:`sandbox.limits.BOUNDS`, or
raises one ``ValueError`` of one line naming the file; ``fit --config`` then
exits with status 2, one line and no traceback, and writes nothing. Examples:
``SANDBOX_HYPOTHESIS_EXAMPLES`` (:mod:`tests.properties`).
"""

from __future__ import annotations

from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from sandbox.cli import main
from sandbox.commands._settings import KEYS, load
from sandbox.limits import BOUNDS
from tests.properties import (
    EXAMPLES,
    SETTINGS,
    assert_clean_refusal,
    documents,
    mutated,
    snapshot,
    write,
)

VALID = {"observe": ["hand"], "n_basis": 9, "regularizer": 0.001, "noise_floor": 0.02,
         "settle_tol": 0.05, "likelihood": "joint", "window_mode": "all", "blend_rate": 50.0,
         "n_candidates": 30, "noise_floors": {"hand": 0.02}}
SUFFIX = st.sampled_from([".yaml", ".json"])


def _check_accepted(got: dict) -> None:
    for key, value in got.items():
        if key == "noise_floors":
            assert all(BOUNDS["noise_floors"].check(v, k) == v for k, v in value)
        elif key in BOUNDS and value is not None:
            assert BOUNDS[key].check(value, key) == value, (key, value)


def _read(path):
    try:
        got = load(path)
    except Exception as error:  # noqa: BLE001 - the property inspects every outcome
        assert_clean_refusal(error, path)
        return None
    _check_accepted(got)
    return got


@SETTINGS
@given(doc=st.one_of(mutated(VALID, KEYS), documents(KEYS)), suffix=SUFFIX)
def test_a_settings_file_is_within_the_table_or_one_line(tmp_path, doc, suffix):
    path = write(tmp_path / f"settings{suffix}", doc)
    before = snapshot(tmp_path)
    _read(path)
    assert snapshot(tmp_path) == before


@SETTINGS
@given(data=st.one_of(st.binary(max_size=300), st.text(max_size=300).map(str.encode)),
       suffix=SUFFIX)
def test_any_bytes_are_a_settings_file_or_one_line(tmp_path, data, suffix):
    path = tmp_path / f"settings{suffix}"
    path.write_bytes(data)
    _read(path)
    assert path.read_bytes() == data


@settings(SETTINGS, max_examples=max(5, EXAMPLES // 3),
          suppress_health_check=[*SETTINGS.suppress_health_check, HealthCheck.filter_too_much])
@given(doc=mutated(VALID, KEYS), suffix=SUFFIX)
def test_fit_exits_2_in_one_line_on_a_refused_settings_file(tmp_path, capsys, doc, suffix):
    path = write(tmp_path / f"settings{suffix}", doc)
    assume(_read(path) is None)
    before = snapshot(tmp_path)
    out = tmp_path / "out" / "m.npz"
    assert main(["fit", "--data", "synthetic:two_task", "--out", str(out), "--config",
                 str(path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: settings ") and err.count("\n") == 1, err
    assert "Traceback" not in err and snapshot(tmp_path) == before
