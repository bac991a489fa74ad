"""Property tests of scenario files: accepted within the table, or refused in one line.

Issue 26 item 1 and issue 29 items 4-5: a scenario with any value changed at
any level (top, ``human``, ``human.tracker``, ``policy``, ``policy.options``,
``model``, ``model.options``), or any document, text or bytes at all, is
either loaded with every number within :data:`sandbox.limits.BOUNDS` or
refused with one ``ValueError`` of one line naming the file and no internal;
the folder is left as it was. Examples: ``SANDBOX_HYPOTHESIS_EXAMPLES``.
"""

from __future__ import annotations

import json

from hypothesis import given
from hypothesis import strategies as st

from sandbox.episodes.scenario_files import TOP_KEYS, load_scenario
from sandbox.limits import BOUNDS
from tests.properties import SETTINGS, assert_clean_refusal, documents, snapshot, write

SYNTHETIC = {"family": "diverging", "seed": 0, "time_limit": 6.0, "speed": 1.0,
             "observe": ["hand"], "human": {"task": "up", "switch_to": "right",
                                            "switch_phase": 0.5},
             "policy": {"type": "dynamic", "dow_t": 0.2, "options": {"blend_rate": 50.0}},
             "model": {"demos": 3, "seed": 0, "options": {"n_basis": 9}}}
SCRIPTED = {**SYNTHETIC, "human": {
    "waypoints": [{"t": 0.0, "position": [1.1, -0.12, 0.25]},
                  {"t": 1.5, "position": [0.8, 0.0, 0.25]}],
    "task": "scripted", "tracker": {"noise_m": 0.002, "glitch_rate": 0.0}},
    "policy": {"type": "static", "ratio": 0.3}}
#: Where a value may be changed, and the keys tried there.
SECTIONS = {(): TOP_KEYS, ("human",): ("task", "switch_to", "switch_phase", "waypoints",
                                       "recorded", "trial", "tracker"),
            ("human", "tracker"): ("noise_m", "glitch_rate", "frame_hz", "glitch_s",
                                   "dropout_rate"),
            ("policy",): ("type", "dow_t", "ratio", "options"),
            ("policy", "options"): ("n_candidates", "refine_steps", "blend_rate", "blend_delay",
                                    "end_prob", "control_hz", "likelihood", "window",
                                    "max_velocity", "until_end", "subsample", "colour"),
            ("model",): ("demos", "seed", "file", "options"),
            ("model", "options"): ("n_basis", "regularizer", "noise_scale", "noise_floor",
                                   "signal_floor", "noise_floors", "settle_tol", "arrive_tol",
                                   "basis_width", "priors", "max_duration", "hue")}


@st.composite
def changed(draw) -> dict:
    """A valid scenario with one value set (to anything) or removed, at any level."""
    doc = json.loads(json.dumps(draw(st.sampled_from([SYNTHETIC, SCRIPTED]))))
    where = draw(st.sampled_from(sorted(SECTIONS)))
    section = doc
    for key in where:
        section = section.setdefault(key, {})
        if not isinstance(section, dict):
            return doc
    key = draw(st.one_of(st.sampled_from(SECTIONS[where]), st.text(max_size=6)))
    if draw(st.integers(0, 4)) == 0:
        section.pop(key, None)
    else:
        section[key] = draw(documents(SECTIONS[where]))
    return doc


def _check_accepted(scenario) -> None:
    for name, value in (("seed", scenario.seed), ("speed", scenario.speed),
                        ("time_limit", scenario.time_limit),
                        ("demos", scenario.model["demos"]), ("seed", scenario.model["seed"])):
        assert BOUNDS[name].check(value, name) == value
    policy = scenario.policy
    key = "dow_t" if policy["type"] == "dynamic" else "ratio"
    assert BOUNDS[key].check(policy[key], key) == policy[key]
    for options in (policy["options"], scenario.model["options"]):
        for name, value in options.items():
            if name in BOUNDS and value is not None:
                assert BOUNDS[name].check(value, name) == value, (name, value)


def _read(path) -> None:
    try:
        scenario = load_scenario(path)
    except Exception as error:  # noqa: BLE001 - the property inspects every outcome
        assert_clean_refusal(error, path)
        return
    _check_accepted(scenario)


SUFFIX = st.sampled_from([".yaml", ".json"])


@SETTINGS
@given(doc=changed(), suffix=SUFFIX)
def test_a_changed_scenario_is_within_the_table_or_one_line(tmp_path, doc, suffix):
    path = write(tmp_path / f"scenario{suffix}", doc)
    before = snapshot(tmp_path)
    _read(path)
    assert snapshot(tmp_path) == before


@SETTINGS
@given(doc=documents(TOP_KEYS), suffix=SUFFIX)
def test_any_document_is_a_scenario_or_one_line(tmp_path, doc, suffix):
    path = write(tmp_path / f"scenario{suffix}", doc)
    _read(path)


@SETTINGS
@given(data=st.one_of(st.binary(max_size=300), st.text(max_size=300).map(str.encode)),
       suffix=SUFFIX)
def test_any_bytes_are_a_scenario_or_one_line(tmp_path, data, suffix):
    path = tmp_path / f"scenario{suffix}"
    path.write_bytes(data)
    _read(path)
    assert path.read_bytes() == data
