"""Property tests of spec files (``--spec``): a spec whose columns can be read, or one line.

Issue 26 item 1 and issue 29 item 5: any spec document (a valid one with a
value changed, any nested document, text or bytes) is either loaded as a
spec whose robot columns are distinct and whose time is none of them, and
whose default modalities can be selected, or refused with one ``ValueError``
of one line naming the file. Examples: ``SANDBOX_HYPOTHESIS_EXAMPLES``.
"""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from sandbox.data.spec import DataSpec
from tests.properties import (
    SETTINGS,
    assert_clean_refusal,
    documents,
    mutated,
    snapshot,
    write,
)

KEYS = ("time", "robot", "observe", "modalities")
VALID = {"time": "stamp", "robot": ["j1", "j2", "j3"], "observe": ["wrist"],
         "modalities": {"wrist": {"columns": ["wx", "wy", "wz"], "kind": "position",
                                  "units": "m"},
                        "grip": {"columns": ["f1", "f2"], "kind": "signal"}}}
SUFFIX = st.sampled_from([".yaml", ".json"])


def _read(path) -> None:
    try:
        spec = DataSpec.load(path)
    except Exception as error:  # noqa: BLE001 - the property inspects every outcome
        assert_clean_refusal(error, path)
        return
    assert len(set(spec.robot)) == len(spec.robot) and spec.time not in spec.robot
    try:
        spec.observed()
    except ValueError as error:        # columns of the observed modalities clash: said so
        assert "\n" not in str(error) and "observe" in str(error)


@st.composite
def modality_changed(draw) -> dict:
    doc = {**VALID, "modalities": {k: dict(v) for k, v in VALID["modalities"].items()}}
    entry = doc["modalities"][draw(st.sampled_from(["wrist", "grip"]))]
    entry[draw(st.sampled_from(["columns", "kind", "units", "extra"]))] = draw(
        documents(("columns", "kind", "units")))
    return doc


@SETTINGS
@given(doc=st.one_of(mutated(VALID, KEYS), modality_changed(), documents(KEYS)), suffix=SUFFIX)
def test_a_spec_file_is_usable_or_one_line(tmp_path, doc, suffix):
    path = write(tmp_path / f"spec{suffix}", doc)
    before = snapshot(tmp_path)
    _read(path)
    assert snapshot(tmp_path) == before


@SETTINGS
@given(data=st.one_of(st.binary(max_size=300), st.text(max_size=300).map(str.encode)),
       suffix=st.sampled_from([".yaml", ".json", ".txt"]))
def test_any_bytes_are_a_spec_or_one_line(tmp_path, data, suffix):
    path = tmp_path / f"spec{suffix}"
    path.write_bytes(data)
    _read(path)
    assert path.read_bytes() == data
