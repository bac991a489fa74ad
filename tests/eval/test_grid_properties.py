"""Property tests of sweep grid files: accepted within the table and the point limit, or one line.

Issue 26 item 1 and issue 29 items 3-4: a grid of lists or of ``points:``
with any value changed, or any document, text or bytes, is either read as at
most :data:`~sandbox.limits.MAX_GRID_POINTS` points whose numbers are each
within :data:`sandbox.limits.BOUNDS`, or refused with one ``ValueError`` of one
line naming the file. Examples: ``SANDBOX_HYPOTHESIS_EXAMPLES``.
"""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from sandbox.eval.grid import KNOWN, read_grid
from sandbox.limits import BOUNDS, MAX_GRID_POINTS
from tests.properties import SETTINGS, assert_clean_refusal, documents, snapshot, write

LISTS = {"n_basis": [9, 15], "noise_floor": [0.01, 0.02], "likelihood": ["joint"],
         "dow_t": [0.2], "observe": ["hand", "hand,arm"], "noise_floors": [{"arm": 0.02}]}
SUFFIX = st.sampled_from([".yaml", ".json"])


@st.composite
def changed(draw) -> dict:
    """A valid grid (lists, or points) with one list or point changed."""
    value = documents(KNOWN)
    key = draw(st.one_of(st.sampled_from(KNOWN), st.text(max_size=6)))
    if draw(st.booleans()):
        doc = {k: list(v) for k, v in LISTS.items()}
        doc[key] = draw(st.one_of(st.lists(value, max_size=6), value))
        return doc
    points = [{"n_basis": 9, "dow_t": 0.2}, {"n_basis": 15, "likelihood": "marginal"}]
    points[draw(st.integers(0, 1))][key] = draw(value)
    return {"points": points}


def _read(path) -> None:
    try:
        points = read_grid(path)
    except Exception as error:  # noqa: BLE001 - the property inspects every outcome
        assert_clean_refusal(error, path)
        return
    assert 1 <= len(points) <= MAX_GRID_POINTS
    for point in points:
        for name, value in point.items():
            if name == "noise_floors":
                assert all(BOUNDS[name].check(f, name) == f for _, f in value)
            elif name in BOUNDS and value is not None:
                assert BOUNDS[name].check(value, name) == value, (name, value)


@SETTINGS
@given(doc=changed(), suffix=SUFFIX)
def test_a_changed_grid_is_within_the_table_or_one_line(tmp_path, doc, suffix):
    path = write(tmp_path / f"grid{suffix}", doc)
    before = snapshot(tmp_path)
    _read(path)
    assert snapshot(tmp_path) == before


@SETTINGS
@given(doc=documents(("points", *KNOWN)), suffix=SUFFIX)
def test_any_document_is_a_grid_or_one_line(tmp_path, doc, suffix):
    _read(write(tmp_path / f"grid{suffix}", doc))


@SETTINGS
@given(sizes=st.lists(st.integers(1, 40), min_size=1, max_size=5))
def test_a_grid_is_refused_exactly_when_its_product_passes_the_limit(tmp_path, sizes):
    from math import prod

    names = ("n_basis", "n_candidates", "refine_steps", "subsample", "blend_rate")
    doc = {name: list(range(3, 3 + n)) for name, n in zip(names, sizes)}
    path = write(tmp_path / "grid.yaml", doc)
    if prod(sizes) > MAX_GRID_POINTS:
        try:
            read_grid(path)
        except ValueError as error:
            assert_clean_refusal(error, path)
            assert "MAX_GRID_POINTS" in str(error)
        else:
            raise AssertionError("a grid past the limit was expanded")
    else:
        assert len(read_grid(path)) == prod(sizes)


@SETTINGS
@given(data=st.one_of(st.binary(max_size=300), st.text(max_size=300).map(str.encode)),
       suffix=SUFFIX)
def test_any_bytes_are_a_grid_or_one_line(tmp_path, data, suffix):
    path = tmp_path / f"grid{suffix}"
    path.write_bytes(data)
    _read(path)
    assert path.read_bytes() == data
