"""The one table of limits (sandbox/limits.py) agrees with every surface that takes a value.

Issue 29 item 4: a scenario's ``model.demos: 10000000`` ran for minutes while
``--demos`` stops at 10,000; ``n_candidates`` was capped at 10,000 in settings,
1,000 in the predictor and not at all in grids. Here every entry of
:data:`sandbox.limits.BOUNDS` is tried at its bounds (accepted) and just past
them (refused with a ``ValueError``, or exit status 2) on the command line, in
settings, scenario and grid files, in the core, the tracker model and the
environments' arguments. A surface that does not take a value is simply not
listed for it.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np
import pytest

from sandbox.limits import BOUNDS, Bound, check

#: Entries whose core check differs from the table, and why (each must still differ:
#: :func:`test_known_differences_are_still_real`).
KNOWN_DIFFERENCES: dict[tuple[str, str], str] = {}


def inside(bound: Bound) -> list[float]:
    """Values at (or, for an open end, just inside) both ends of ``bound``."""
    low = bound.low if not bound.open_low else (1 if bound.integer else bound.low + 1e-9)
    return [low, bound.high]


def outside(bound: Bound) -> list[float]:
    """Values just past both ends of ``bound``."""
    if bound.integer:
        return [bound.low - 1, bound.high + 1]
    below = bound.low if bound.open_low else bound.low - max(1e-9, abs(bound.low) * 1e-6)
    return [below, bound.high * (1 + 1e-6) + 1e-9]


def test_bound_checks_and_messages():
    assert check("n_basis", 100) == 100 and check("n_basis", 7.0) == 7
    assert check("seed", 2**63 - 1) == 2**63 - 1
    for bad in (101, 1, 7.5, True, "7", None, math.nan, math.inf, 2**200):
        with pytest.raises(ValueError, match=r"^n_basis: expected an integer in \[2, 100\], "
                                             r"got .* \(sandbox.limits\)$"):
            check("n_basis", bad)
    with pytest.raises(ValueError, match=r"expected a finite number in \(0, 1\], got 0"):
        check("ratio", 0)
    assert check("ratio", np.float32(0.5)) == 0.5 and check("n_basis", np.int64(5)) == 5


# --------------------------------------------------------------------------- surfaces


def _cli_options() -> dict[str, list[tuple[list[str], str]]]:
    """Table entry -> (command words, option) of the real parsers (``bounded`` types)."""
    from sandbox.cli import build_parser
    from sandbox.commands import _types

    types = {id(getattr(_types, name)): entry for name, entry in (
        ("WORKERS", "workers"), ("SEED", "seed"), ("PER_TASK", "n_per_task"),
        ("DEMOS", "demos"), ("N_BASIS", "n_basis"), ("REGULARIZER", "regularizer"),
        ("SECONDS", "dow_t"), ("FRACTION", "ratio"), ("SWITCH", "switch_phase"),
        ("WINDOWS", "dow_t"), ("RATIOS", "ratio"), ("EPISODE", "time_limit"))}
    out: dict[str, list[tuple[list[str], str]]] = {}

    def walk(parser, words):
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, child in action.choices.items():
                    walk(child, [*words, name])
            elif action.option_strings and id(action.type) in types:
                out.setdefault(types[id(action.type)], []).append(
                    (words, action.option_strings[-1]))
    walk(build_parser(), [])
    return out


CLI = _cli_options()


def test_the_cli_uses_the_table_for_every_shared_option():
    assert {"workers", "seed", "n_per_task", "demos", "n_basis", "regularizer", "dow_t",
            "ratio", "switch_phase", "time_limit"} <= set(CLI)
    assert any(option == "--demos" for words, option in CLI["demos"])
    assert any(option == "--windows" for words, option in CLI["dow_t"])


@pytest.mark.parametrize("name", sorted(CLI))
def test_cli_options_agree_with_the_table(name, capsys):
    from sandbox.cli import build_parser

    parser, bound = build_parser(), BOUNDS[name]
    for words, option in CLI[name]:
        for value in inside(bound):
            text = str(int(value)) if bound.integer else repr(float(value))
            assert _parses(parser, words, option, text), (words, option, text)
        for value in outside(bound):
            text = str(int(value)) if bound.integer else repr(float(value))
            assert not _parses(parser, words, option, text), (words, option, text)
            assert option in capsys.readouterr().err


def _parses(parser: argparse.ArgumentParser, words: list[str], option: str, text: str) -> bool:
    """Whether ``option text`` gets past the option's own type (other errors do not count)."""
    child = parser
    for word in words:
        child = next(a for a in child._actions
                     if isinstance(a, argparse._SubParsersAction)).choices[word]
    action = next(a for a in child._actions if option in a.option_strings)
    try:
        action.type(text)
    except argparse.ArgumentTypeError:
        with pytest.raises(SystemExit) as info:
            parser.parse_args([*words, f"{option}={text}"])
        assert info.value.code == 2
        return False
    return True


SETTINGS = ("n_basis", "n_candidates", "refine_steps", "subsample", "regularizer", "noise_scale",
            "noise_floor", "signal_floor", "blend_rate", "blend_delay", "end_prob",
            "settle_tol", "arrive_tol", "jitter_floor")


@pytest.mark.parametrize("name", SETTINGS)
def test_settings_files_agree_with_the_table(tmp_path, name):
    from sandbox.commands._settings import NUMBERS, load

    assert set(NUMBERS) == set(SETTINGS)
    path = tmp_path / "s.json"
    for value in inside(BOUNDS[name]):
        path.write_text(json.dumps({name: value}))
        assert load(path)[name] == value
    for value in outside(BOUNDS[name]):
        path.write_text(json.dumps({name: value}))
        with pytest.raises(ValueError, match=f"settings {path}: {name}: expected"):
            load(path)


def test_settings_noise_floors_agree_with_the_table(tmp_path):
    from sandbox.commands._settings import load

    path = tmp_path / "s.json"
    for value in inside(BOUNDS["noise_floors"]):
        path.write_text(json.dumps({"observe": ["hand", "arm"], "noise_floors": {"arm": value}}))
        assert load(path)["noise_floors"] == (("arm", value),)
    for value in outside(BOUNDS["noise_floors"]):
        path.write_text(json.dumps({"noise_floors": {"arm": value}}))
        with pytest.raises(ValueError, match=r"noise_floors\['arm'\]: expected"):
            load(path)


GRID = (*SETTINGS, "noise_floors", "dow_t", "ratio")


@pytest.mark.parametrize("name", GRID)
def test_grid_files_agree_with_the_table(name):
    from sandbox.eval.grid import parse_grid

    def grid(value):
        return {name: [{"arm": value} if name == "noise_floors" else value]}

    for value in inside(BOUNDS[name]):
        (point,) = parse_grid(grid(value))
        assert point[name] == ((("arm", value),) if name == "noise_floors" else value)
    for value in outside(BOUNDS[name]):
        with pytest.raises(ValueError, match=f"^{name}.*: expected"):
            parse_grid(grid(value))


#: Scenario keys (a path into the file) -> table entry.
SCENARIO = {
    ("seed",): "seed", ("speed",): "speed", ("time_limit",): "time_limit",
    ("human", "switch_phase"): "switch_phase", ("policy", "dow_t"): "dow_t",
    ("model", "demos"): "demos", ("model", "seed"): "seed",
    ("policy", "options", "n_candidates"): "n_candidates",
    ("policy", "options", "refine_steps"): "refine_steps",
    ("policy", "options", "blend_rate"): "blend_rate",
    ("policy", "options", "blend_delay"): "blend_delay",
    ("policy", "options", "end_prob"): "end_prob",
    ("policy", "options", "control_hz"): "control_hz",
    ("model", "options", "n_basis"): "n_basis",
    ("model", "options", "regularizer"): "regularizer",
    ("model", "options", "noise_scale"): "noise_scale",
    ("model", "options", "noise_floor"): "noise_floor",
    ("model", "options", "signal_floor"): "signal_floor",
    ("model", "options", "settle_tol"): "settle_tol",
    ("model", "options", "arrive_tol"): "arrive_tol",
}
BASE_SCENARIO = {"family": "diverging", "human": {"task": "up"},
                 "policy": {"type": "dynamic", "dow_t": 0.2}, "model": {"demos": 3}}
WAYPOINTS = {("t",): "waypoint_t", ("position",): "position", ("tracker", "noise_m"): "noise_m",
             ("tracker", "glitch_rate"): "glitch_rate", ("tracker", "frame_hz"): "frame_hz"}


def _with(data: dict, keys: tuple[str, ...], value) -> dict:
    data = json.loads(json.dumps(data))
    inner = data
    for key in keys[:-1]:
        inner = inner.setdefault(key, {})
    inner[keys[-1]] = value
    return data


def _scenario_accepts(tmp_path: Path, data: dict) -> bool:
    from sandbox.episodes.scenario_files import load_scenario

    path = tmp_path / "s.json"
    path.write_text(json.dumps(data))
    try:
        load_scenario(path)
    except ValueError as error:
        assert str(error).startswith(f"scenario {path}: ") and "\n" not in str(error)
        return False
    return True


@pytest.mark.parametrize("keys", sorted(SCENARIO), ids=".".join)
def test_scenario_files_agree_with_the_table(tmp_path, keys):
    bound = BOUNDS[SCENARIO[keys]]
    for value in inside(bound):
        assert _scenario_accepts(tmp_path, _with(BASE_SCENARIO, keys, value)), value
    for value in outside(bound):
        assert not _scenario_accepts(tmp_path, _with(BASE_SCENARIO, keys, value)), value


@pytest.mark.parametrize("keys", sorted(WAYPOINTS), ids=".".join)
def test_scripted_scenarios_agree_with_the_table(tmp_path, keys):
    bound = BOUNDS[WAYPOINTS[keys]]

    def scenario(value):
        first = {"t": 0.0, "position": [1.1, -0.1, 0.25]}
        last = {"t": 700.0 if keys == ("t",) else 1.5, "position": [0.8, 0.0, 0.25]}
        human = {"waypoints": [first, last]}
        if keys == ("t",):
            first["t"] = value
            last["t"] = max(value, 0) + 1.0
        elif keys == ("position",):
            first["position"] = [value, 0.0, 0.25]
        else:
            human = _with(human, keys, value)
        return {**BASE_SCENARIO, "human": human}

    for value in inside(bound):
        data = scenario(value)
        if keys == ("t",) and value == bound.high:     # the last waypoint would pass it
            data["human"]["waypoints"] = [{"t": 0.0, "position": [1.1, -0.1, 0.25]},
                                          {"t": value, "position": [0.8, 0.0, 0.25]}]
        assert _scenario_accepts(tmp_path, data), value
    for value in outside(bound):
        assert not _scenario_accepts(tmp_path, scenario(value)), value


MODEL = ("n_basis", "regularizer", "noise_scale", "noise_floor", "signal_floor", "settle_tol",
         "arrive_tol", "jitter_floor")


@pytest.mark.parametrize("name", MODEL)
def test_the_core_model_agrees_with_the_table(name):
    from sandbox.core import IProMP

    for value in inside(BOUNDS[name]):
        IProMP(**{name: value})
    for value in outside(BOUNDS[name]):
        with pytest.raises(ValueError, match=name):
            IProMP(**{name: value})
    with pytest.raises(ValueError, match="noise_floors"):
        IProMP(noise_floors={"arm": outside(BOUNDS["noise_floors"])[1]})


@pytest.fixture(scope="module")
def fitted():
    from sandbox.core import IProMP
    from sandbox.data.synthetic import two_task_demos

    return IProMP(n_basis=7).fit(two_task_demos(4, np.random.default_rng(0)))


PREDICTOR = ("n_candidates", "refine_steps", "subsample", "blend_rate", "blend_delay",
             "end_prob", "dow_t", "ratio")


@pytest.mark.parametrize("name", PREDICTOR)
def test_the_core_predictors_agree_with_the_table(fitted, name):
    if ("core", name) in KNOWN_DIFFERENCES:
        pytest.skip(KNOWN_DIFFERENCES[("core", name)])
    from sandbox.core import DynamicPredictor, StaticPredictor

    make = StaticPredictor if name == "ratio" else DynamicPredictor
    for value in inside(BOUNDS[name]):
        make(fitted, **{name: value})
    for value in outside(BOUNDS[name]):
        with pytest.raises(ValueError, match=name):
            make(fitted, **{name: value})


def test_the_core_window_is_the_tables(fitted):
    """The one difference the merge of issue 29 left (DynamicPredictor's own 1e-4 s floor and
    no ceiling) is gone: the core reads ``BOUNDS["dow_t"]`` too."""
    from sandbox.core import DynamicPredictor

    assert not KNOWN_DIFFERENCES
    with pytest.raises(ValueError, match="dow_t"):
        DynamicPredictor(fitted, dow_t=outside(BOUNDS["dow_t"])[1])
    assert DynamicPredictor(fitted, dow_t=BOUNDS["dow_t"].high).dow_t == 60.0


@pytest.mark.parametrize("name", ["noise_m", "glitch_rate", "frame_hz"])
def test_the_tracker_model_agrees_with_the_table(name):
    from sandbox.data.synthetic.tracker import TrackerModel

    for value in inside(BOUNDS[name]):
        TrackerModel(**{name: value})
    for value in outside(BOUNDS[name]):
        with pytest.raises(ValueError, match=name):
            TrackerModel(**{name: value})


def test_the_environments_control_rate_agrees_with_the_table():
    from sandbox.envs.arguments import check_control_hz

    for value in inside(BOUNDS["control_hz"]):
        assert check_control_hz(value) == value
    for value in (*outside(BOUNDS["control_hz"]), 1e-6):
        with pytest.raises(ValueError, match="control_hz"):
            check_control_hz(value)


def test_the_core_constants_are_the_tables():
    from sandbox.core import limits as core
    from sandbox.core.updating import MAX_REFINE_STEPS

    assert core.MAX_N_BASIS == BOUNDS["n_basis"].high
    assert core.MAX_CANDIDATES == BOUNDS["n_candidates"].high
    assert core.MAX_SUBSAMPLE == BOUNDS["subsample"].high
    assert MAX_REFINE_STEPS == BOUNDS["refine_steps"].high
    assert core.MIN_REGULARIZER == BOUNDS["regularizer"].low
    assert core.MAX_RELATIVE == BOUNDS["noise_scale"].high == BOUNDS["regularizer"].high
    assert core.MIN_NOISE_STD == BOUNDS["noise_floor"].low == BOUNDS["signal_floor"].low
    assert BOUNDS["time_limit"].high == core.MAX_TIME_S    # an episode fits a predictor
    assert BOUNDS["dow_t"].high == core.MAX_DURATION_S


def test_the_table_is_documented():
    import sandbox.limits as module

    doc = module.__doc__ or ""
    for name in BOUNDS:
        assert f"``{name}``" in doc, name


@pytest.mark.parametrize("name, word", [("span_reg", "auto"), ("post_end", "span")])
def test_the_factor_options_agree_with_the_table_in_the_core_and_settings(tmp_path, name, word):
    """``span_reg`` and ``post_end``: a factor in the table's range, their word or null, one
    check for the model and settings files (sandbox.limits.check_factor)."""
    from sandbox.commands._settings import FACTORS, load
    from sandbox.core import IProMP

    assert FACTORS[name] == word
    path = tmp_path / "s.json"
    for value in (*inside(BOUNDS[name]), word, None):
        assert getattr(IProMP(**{name: value}), name) == value
        path.write_text(json.dumps({name: value}))
        assert load(path)[name] == value
    for value in (*outside(BOUNDS[name]), "other", True, [1.0]):
        with pytest.raises(ValueError, match=f"{name}: expected a factor in .0, 10., {word} or"):
            IProMP(**{name: value})
        path.write_text(json.dumps({name: value}))
        with pytest.raises(ValueError, match=f"settings {path}: {name}: expected a factor"):
            load(path)
