"""The metadata of a model file (:mod:`sandbox.core.io`), checked before any array is read.

:func:`check_metadata` takes the parsed JSON and returns it checked: format and
version, basis, hyperparameters, dims, modalities against ``n_human``, robot
names, and each task's entry: names, durations, the speed prior as
:meth:`IProMP.fit <sandbox.core.model.IProMP.fit>` makes it, priors summing to 1.
Only numpy and the core's own checks.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from sandbox.core.basis import GaussianBasis
from sandbox.core.limits import (
    MAX_ALPHA_STD,
    MAX_DIMS,
    MAX_TASKS,
    MAX_TIME_S,
    MIN_ALPHA_STD,
    MIN_MEDIAN_DT_S,
    check_alpha_std,
)
from sandbox.core.modality import Modality, check_modalities, default_modalities
from sandbox.core.posthold import check_post_var
from sandbox.validation import check_number

FORMAT = "handover-sandbox/iprompt"
FORMAT_VERSION = 2
READABLE_VERSIONS = (1, 2)
#: Hyperparameters each format version stores (the IProMP options).
HYPERPARAMETERS = {
    1: {"regularizer", "noise_scale", "noise_floor", "min_alpha_std", "ridge"},
    2: {"regularizer", "noise_scale", "noise_floor", "signal_floor", "noise_floors",
        "jitter_floor", "settle_tol", "arrive_tol", "min_alpha_std", "shrinkage", "ridge",
        "condition_floor", "span_reg", "post_end"},
}
TASK_KEYS = {"name", "nominal_duration", "alpha_mean", "alpha_std", "n_demos", "prior"}
#: Spaces a model's robot dims may be in: joint angles (rad) or a task-space position (m).
ROBOT_SPACES = ("joint", "task")
#: How far from 1 the stored priors may sum.
PRIOR_TOLERANCE = 1e-6
#: How far from 1 a stored ``alpha_mean`` may be (a fit writes exactly 1).
ALPHA_MEAN_TOLERANCE = 1e-9


def check_metadata(meta, path: Path) -> dict:
    """A model file's parsed metadata, checked: every field of the expected type and range,
    the speed priors within what a fit makes (:func:`_check_speed`)."""
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        got = meta.get("format") if isinstance(meta, dict) else type(meta).__name__
        raise ValueError(f"{str(path)!r} is not a handover-sandbox model (format {got!r})")
    version = meta.get("format_version")
    if type(version) is not int or version not in READABLE_VERSIONS:
        raise ValueError(f"model file {str(path)!r} has format version {version!r}; this "
                         f"version of the package reads versions {list(READABLE_VERSIONS)}")
    need = ["basis", "hyperparameters", "n_human", "n_robot", "tasks", "robot_names"]
    need += ["modalities"] if version >= 2 else []
    for key in need:
        if key not in meta:
            raise ValueError(f"metadata lacks {key!r}")
    P, Q = _count(meta["n_human"], "n_human"), _count(meta["n_robot"], "n_robot")
    return {"format_version": version, "basis": GaussianBasis.from_dict(meta["basis"]).to_dict(),
            "hyperparameters": _hyperparameters(meta["hyperparameters"], version),
            "n_human": P, "n_robot": Q, "modalities": _modalities(meta, P),
            "robot_names": _names(meta["robot_names"], "robot_names", (0, Q)),
            "robot_space": _space(meta.get("robot_space", "joint")),
            "tasks": _tasks(meta["tasks"], _min_alpha_std(meta["hyperparameters"])),
            "familiarity": meta.get("familiarity"),
            "session": _session(meta.get("session", {})),
            "floors_used": _floors_used(meta.get("floors_used"), P),
            "condition_noise": _floors_used(meta.get("condition_noise"), P, "condition_noise"),
            "span_used": _span_used(meta.get("span_used")),
            "post_var": check_post_var(meta, len(meta["modalities"]) if version >= 2 else 1)}




def _check_speed(where: str, nominal: float, a_mean: float, a_std: float, n_demos: int,
                 min_alpha_std: float) -> None:
    """The speed prior's statistics within what :meth:`IProMP.fit` can make of n demos.

    A fit's nominal duration is the mean of its demos' (each at least two samples
    ``limits.MIN_MEDIAN_DT_S`` apart), so ``alpha_mean`` is 1; ``alpha_std`` is the
    spread of n positive durations over their mean (below sqrt(n)), floored at
    ``min_alpha_std``, at most ``limits.MAX_ALPHA_STD``.
    """
    if nominal < MIN_MEDIAN_DT_S:
        raise ValueError(f"{where} nominal_duration: expected at least {MIN_MEDIAN_DT_S:g} s "
                         f"(limits.MIN_MEDIAN_DT_S), got {nominal:g}")
    if abs(a_mean - 1.0) > ALPHA_MEAN_TOLERANCE:
        raise ValueError(f"{where} alpha_mean: expected 1 (the nominal duration is the demos' "
                         f"mean), got {a_mean:g}")
    high = min(max(float(np.sqrt(n_demos)), min_alpha_std), MAX_ALPHA_STD)
    if not min_alpha_std <= a_std <= high:
        raise ValueError(f"{where} alpha_std: expected a speed-factor spread in "
                         f"[{min_alpha_std:g}, {high:.4g}] (min_alpha_std to what {n_demos} "
                         f"demonstrations can give, limits.MAX_ALPHA_STD {MAX_ALPHA_STD:g}), "
                         f"got {a_std:g}")


def _floors_used(value, P: int, name: str = "floors_used") -> list | None:
    """``floors_used``: the P floors a ``noise_floor="auto"`` fit learned (absent before);
    likewise ``condition_noise``, the P variances of a ``condition_floor``."""
    if value is None:
        return None
    ok = isinstance(value, list) and len(value) == P and all(
        isinstance(v, (int, float)) and not isinstance(v, bool) and 0 < v < np.inf
        for v in value)
    if not ok:
        raise ValueError(f"metadata {name}: expected {P} positive numbers, "
                         f"got {str(value)[:60]}")
    return value


def _span_used(value) -> dict | None:
    """``span_used``: per modality name, ``variance`` (a non-negative number or null) and
    ``factor`` (a non-negative number), and the held-out ``scores`` of ``span_reg="auto"``."""
    if value is None:
        return None

    def number(v, null: bool = False) -> bool:
        return (v is None and null) or (isinstance(v, (int, float)) and not isinstance(v, bool)
                                        and 0 <= v < np.inf)

    ok = isinstance(value, dict) and all(
        isinstance(k, str) and isinstance(e, dict) and number(e.get("variance"), True)
        and number(e.get("factor")) and set(e) <= {"variance", "factor", "scores"}
        for k, e in value.items())
    if not ok:
        raise ValueError(f"metadata span_used: expected per modality a variance and a factor, "
                         f"got {str(value)[:60]}")
    return value


def _space(value) -> str:
    """``robot_space``: what the robot dims are (absent in files before it: ``joint``)."""
    if value not in ROBOT_SPACES:
        raise ValueError(f"metadata robot_space: expected one of {list(ROBOT_SPACES)}, "
                         f"got {str(value)[:40]!r}")
    return value


def _session(entry) -> dict:
    if not isinstance(entry, dict):
        raise ValueError(f"metadata session: expected an object, got {type(entry).__name__}")
    return entry


def _count(value, name: str) -> int:
    if type(value) is not int or not 1 <= value <= MAX_DIMS:
        raise ValueError(f"metadata {name}: expected an integer in [1, {MAX_DIMS}], "
                         f"got {value!r}")
    return value


def _names(value, name: str, sizes: tuple[int, ...]) -> list[str]:
    if (not isinstance(value, list) or len(value) not in sizes
            or not all(isinstance(v, str) for v in value)):
        raise ValueError(f"metadata {name}: expected a list of {' or '.join(map(str, sizes))} "
                         f"names, got {str(value)[:60]}")
    return value


def _hyperparameters(hyper, version: int) -> dict:
    known = HYPERPARAMETERS[version]
    if not isinstance(hyper, dict) or not set(hyper) <= known:
        got = sorted(map(str, set(hyper) - known)) if isinstance(hyper, dict) else hyper
        raise ValueError(f"metadata hyperparameters: expected keys among {sorted(known)}, "
                         f"got {got!r}")
    return hyper


def _modalities(meta: dict, P: int) -> tuple:
    if meta["format_version"] == 1:
        names = tuple(_names(meta.get("human_names") or [], "human_names", (0, P)))
        names = names or tuple(f"human_{i}" for i in range(P))
        return check_modalities(default_modalities(names), P)
    mods = meta["modalities"]
    if not isinstance(mods, list):
        raise ValueError(f"metadata modalities: expected a list, got {type(mods).__name__}")
    return check_modalities([Modality.from_dict(m) for m in mods], P)


def _min_alpha_std(hyper) -> float:
    """The file's ``min_alpha_std`` (checked by the model's constructor), else the limit's."""
    value = hyper.get("min_alpha_std") if isinstance(hyper, dict) else None
    try:
        return check_alpha_std(value)
    except ValueError:
        return MIN_ALPHA_STD


def _tasks(tasks, min_alpha_std: float) -> list[dict[str, Any]]:
    """Task entries: names, durations, speed priors as a fit makes them, priors summing to 1."""
    if not isinstance(tasks, list) or not 1 <= len(tasks) <= MAX_TASKS:
        raise ValueError(f"metadata tasks: expected a list of 1 to {MAX_TASKS} tasks, got "
                         f"{str(tasks)[:60]}")
    out: list[dict[str, Any]] = []
    for i, t in enumerate(tasks):
        if not isinstance(t, dict) or set(t) != TASK_KEYS:
            raise ValueError(f"metadata tasks[{i}]: expected the keys {sorted(TASK_KEYS)}, got "
                             f"{sorted(map(str, t)) if isinstance(t, dict) else t!r}")
        name = t["name"]
        if not isinstance(name, str) or not name:
            raise ValueError(f"metadata tasks[{i}].name: expected a non-empty name, got {name!r}")
        where = f"metadata task {name!r}"
        nominal = check_number(t["nominal_duration"], f"{where} nominal_duration",
                               low=0.0, high=MAX_TIME_S)
        a_mean = check_number(t["alpha_mean"], f"{where} alpha_mean", low=0.0)
        a_std = check_number(t["alpha_std"], f"{where} alpha_std", low=0.0)
        if nominal <= 0 or a_mean <= 0 or a_std <= 0 or a_mean * nominal > MAX_TIME_S:
            raise ValueError(f"{where}: expected nominal_duration, alpha_mean and alpha_std "
                             f"> 0 and a mean duration within {MAX_TIME_S:g} s, got "
                             f"{nominal:g}, {a_mean:g}, {a_std:g}")
        n_demos = t["n_demos"]
        if type(n_demos) is not int or n_demos < 2:
            raise ValueError(f"{where} n_demos: expected an integer >= 2 (a fit needs two "
                             f"demonstrations per task), got {n_demos!r}")
        _check_speed(where, nominal, a_mean, a_std, n_demos, min_alpha_std)
        prior = check_number(t["prior"], f"{where} prior", low=0.0, high=1.0)
        out.append({"name": name, "nominal_duration": nominal, "alpha_mean": a_mean,
                    "alpha_std": a_std, "n_demos": n_demos, "prior": prior})
    names = [t["name"] for t in out]
    if len(set(names)) != len(names):
        raise ValueError(f"metadata tasks: names repeat in {names}")
    total = sum(t["prior"] for t in out)
    if abs(total - 1.0) > PRIOR_TOLERANCE:
        raise ValueError(f"metadata priors: expected a probability vector (summing to 1), got "
                         f"{[t['prior'] for t in out]} (sum {total:g})")
    return out
