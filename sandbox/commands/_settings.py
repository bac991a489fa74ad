"""Settings files: what ``tune --out FILE`` chose, applied by ``--config FILE``.

A settings file is one YAML or JSON mapping (by suffix) of model and
predictor options, the names of :class:`~sandbox.eval.loocv.EvalConfig`::

    observe: [hand]          # modalities (or "hand,arm")
    n_basis: 21              # model (IProMP) options
    regularizer: 0.001
    span_reg: auto           # null, a factor, or auto: regulariser from the out-of-span variance
    post_end: null           # null, a factor or span: observations past the end share one offset
    noise_floor: 0.02        # m, or auto: learned per position modality from the demos
    condition_floor: auto    # m, auto or null: the floor conditioning the robot (eq. 7-9)
    jitter_floor: 15         # position floors max(noise_floor, 15 x raw jitter); null: off
    shrinkage: auto          # auto | none | robot: covariances shrunk toward the pooled one
    settle_tol: 0.05         # rad, or null: the whole recording is the motion
    likelihood: joint        # predictor options: joint | marginal
    window_mode: all         # all | latest
    blend_rate: 50.0         # 1/s

Every key is optional; an unknown key is an error naming it and the valid
ones. ``fit`` uses the model options and ``observe``; ``evaluate`` and
``sweep`` all of them (a sweep's grid values replace them); ``play`` the
model options (when it fits its model), ``observe`` and the predictor options
but ``subsample`` and ``until_end``, which stay those of the closed-loop
policy. A flag given on the command line (``--observe``, ``--n-basis``,
``--regularizer``) overrides the file: those flags default to None, so a
value that is not None was typed.
"""

from __future__ import annotations

import argparse
from collections.abc import Mapping
from pathlib import Path
from typing import Any

#: Options of the model (:class:`~sandbox.core.IProMP`).
MODEL_KEYS = ("n_basis", "regularizer", "span_reg", "post_end", "noise_scale", "noise_floor",
              "condition_floor", "signal_floor", "noise_floors", "jitter_floor", "shrinkage",
              "settle_tol", "arrive_tol")
#: Options of the predictor (:class:`~sandbox.core.DynamicPredictor`).
PREDICTOR_KEYS = ("likelihood", "window_mode", "n_candidates", "refine_steps", "blend_rate",
                  "blend_delay", "until_end", "end_prob", "subsample")
#: Every key a settings file may hold.
KEYS = ("observe", *MODEL_KEYS, *PREDICTOR_KEYS)
#: Predictor options ``play`` takes from a file (the others are the closed loop's own).
PLAY_PREDICTOR_KEYS = ("likelihood", "window_mode", "n_candidates", "refine_steps",
                       "blend_rate", "blend_delay", "end_prob")
CHOICES = {"likelihood": ("joint", "marginal"), "window_mode": ("all", "latest"),
           "shrinkage": ("auto", "none", "robot")}   # sandbox.core.shrinkage.SHRINKAGE
#: Keys whose values are numbers, each in its range of :data:`sandbox.limits.BOUNDS`
#: (``None`` allowed for the tolerances: "not used").
NUMBERS = ("n_basis", "n_candidates", "refine_steps", "subsample", "regularizer", "noise_scale",
           "noise_floor", "signal_floor", "blend_rate", "blend_delay", "end_prob",
           "settle_tol", "arrive_tol", "jitter_floor")
OPTIONAL = ("settle_tol", "arrive_tol", "jitter_floor")
#: Keys that take a factor in their range of :data:`sandbox.limits.BOUNDS`, this word, or null.
FACTORS = {"span_reg": "auto", "post_end": "span"}     # spanreg.AUTO, posthold.SPAN


def add_argument(parser: argparse.ArgumentParser) -> None:
    """Add ``--config FILE``."""
    parser.add_argument("--config", default=None, metavar="FILE",
                        help="settings file (YAML/JSON) written by 'python -m sandbox tune "
                             "--out FILE'; options given here override it")


def load(path: str | Path | None) -> dict[str, Any]:
    """The checked settings of ``path`` (``{}`` for None); errors name the file and key."""
    if path is None:
        return {}
    from sandbox.validation import is_file, read_mapping

    path = Path(path)
    if not is_file(path):
        raise ValueError(f"--config: expected an existing settings file (.yaml/.json), "
                         f"got {str(path)!r}")
    data = read_mapping(path, "settings")
    if data is None:
        return {}
    if not isinstance(data, Mapping):
        raise ValueError(f"settings {path}: expected a mapping of options, got {_show(data)}")
    unknown = sorted(_show(k) for k in data if k not in KEYS)
    if unknown:
        raise ValueError(f"settings {path}: unknown key {unknown[0]}; valid keys: "
                         f"{', '.join(KEYS)}")
    settings = {k: _check(path, k, v) for k, v in data.items()}
    _check_floors(path, settings)
    _check_model(path, settings)
    return settings


def _check(path: Path, key: str, value: Any) -> Any:
    from sandbox.limits import BOUNDS

    def fail(expected: str):
        return ValueError(f"settings {path}: {key}: expected {expected}, got {_show(value)}")

    if key == "observe":
        names = value.split(",") if isinstance(value, str) else value
        if not isinstance(names, list) or not names or not all(
                isinstance(n, str) and n.strip() for n in names):
            raise fail("a list of modality names")
        return tuple(n.strip() for n in names)
    if key == "noise_floors":
        if not isinstance(value, Mapping) or not all(
                isinstance(k, str) and k.strip() for k in value):
            raise fail("a mapping of modality names to floors")
        return tuple(sorted((k, _bounded(path, f"noise_floors[{k!r}]", "noise_floors", v))
                            for k, v in value.items()))
    if key in CHOICES:
        if value not in CHOICES[key]:
            raise fail(f"one of {list(CHOICES[key])}")
        return value
    if key == "until_end":
        if not isinstance(value, bool):
            raise fail("true or false")
        return value
    if key == "noise_floor" and isinstance(value, str) and not _numeric(value):
        if value != "auto":
            raise fail("a number (m) or auto")
        return value
    if key in FACTORS:                  # sandbox.limits.check_factor's range and words
        from sandbox.limits import check_factor

        if isinstance(value, str) and _numeric(value):
            value = float(value)
        try:
            return check_factor(key, value, FACTORS[key])
        except ValueError as error:
            raise ValueError(f"settings {path}: {error}") from None
    if key == "condition_floor":
        if value is None or value == "auto":
            return value
        if isinstance(value, str) and not _numeric(value):
            raise fail("a number (m), auto or null")
        return _bounded(path, key, "noise_floor", value)
    if value is None and key in OPTIONAL:
        return None
    assert key in NUMBERS and key in BOUNDS, key
    return _bounded(path, key, key, value)


def _bounded(path: Path, label: str, key: str, value: Any) -> Any:
    """``value`` in the range of ``key`` (:mod:`sandbox.limits`); YAML 1.1 ``1e-3`` is a number."""
    from sandbox.limits import check

    if isinstance(value, str):
        try:
            value = float(value)
        except ValueError:
            pass
    try:
        return check(key, value, label, or_null=key in OPTIONAL)
    except ValueError as error:
        raise ValueError(f"settings {path}: {error}") from None


def _numeric(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _show(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _check_floors(path: Path, settings: dict) -> None:
    """Floors only for modalities the file observes (when it names them)."""
    named = {k for k, _ in settings.get("noise_floors", ())}
    observed = set(settings.get("observe", named))
    if named - observed:
        raise ValueError(f"settings {path}: noise_floors: expected floors of the observed "
                         f"modalities {sorted(observed)}, got {sorted(named - observed)}")


def _check_model(path: Path, settings: dict) -> None:
    """The core's own checks of the model options (ranges it alone knows)."""
    from sandbox.core import IProMP

    try:
        IProMP(**model_options(settings))
    except ValueError as error:
        raise ValueError(f"settings {path}: {error}") from None


def model_options(settings: dict, **explicit) -> dict[str, Any]:
    """:class:`~sandbox.core.IProMP` keywords of ``settings``, ``explicit`` ones (not None)
    replacing them."""
    out = {k: v for k, v in settings.items() if k in MODEL_KEYS}
    if "noise_floors" in out:
        out["noise_floors"] = dict(out["noise_floors"])
    out.update({k: v for k, v in explicit.items() if v is not None})
    return out


def eval_fields(settings: dict) -> dict[str, Any]:
    """:class:`~sandbox.eval.loocv.EvalConfig` fields of ``settings`` (all but ``observe``)."""
    return {k: v for k, v in settings.items() if k != "observe"}


def predictor_options(settings: dict) -> dict[str, Any]:
    """Policy (:class:`~sandbox.core.DynamicPredictor`) keywords ``play`` takes from a file."""
    out = {k: v for k, v in settings.items() if k in PLAY_PREDICTOR_KEYS}
    if "window_mode" in out:
        out["window"] = out.pop("window_mode")
    return out


def observe(explicit: str | None, settings: dict) -> str | None:
    """``--observe`` if given, else the file's ``observe`` (as ``"a,b"``), else None."""
    if explicit is not None:
        return explicit
    return ",".join(settings["observe"]) if "observe" in settings else None


def to_file(chosen: dict[str, Any], observe, path: str | Path, comment: str) -> None:
    """Write ``chosen`` (EvalConfig option -> value) and ``observe`` as a settings file."""
    from sandbox.commands._outputs import write_text

    data: dict[str, Any] = {"observe": list(observe)}
    for key, value in chosen.items():
        if key not in KEYS:
            raise ValueError(f"settings: {key!r} is not a settings key ({', '.join(KEYS)})")
        data[key] = dict(value) if key == "noise_floors" else value
    path = Path(path)
    if path.suffix.lower() == ".json":
        import json

        text = json.dumps(data, indent=1) + "\n"
    else:
        import yaml

        text = "".join(f"# {line}\n" for line in comment.splitlines())
        text += yaml.safe_dump(data, sort_keys=False, default_flow_style=None)
    write_text(path, text)
