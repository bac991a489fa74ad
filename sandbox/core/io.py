"""Saving and loading fitted models: ``.npz`` arrays + JSON metadata, never pickle.

Layout of the file (a numpy ``.npz`` archive, written atomically; any reader of
``.npz`` can open it with ``allow_pickle=False``):

* ``metadata``: a 0-d unicode array holding JSON with ``format`` (=
  :data:`FORMAT`), ``format_version`` (= :data:`FORMAT_VERSION`), the basis,
  the hyperparameters, the modalities (name, dims, kind, units), names of the
  robot dims, per-task durations and priors;
* ``noise``: :math:`\\sigma_p^2` (normalised units), shape (P,);
* ``scale``: the scale of every human dim (signal normaliser; 1 for positions), shape (P,);
* for task i: ``task{i}_mean`` (D*N,), ``task{i}_factor`` (D*N, r), ``task{i}_reg`` (D,).

Optional, for a model with a familiarity calibration
(:mod:`sandbox.core.familiarity`): a ``familiarity`` entry in the metadata
(threshold, alpha, likelihood, subsample, dow_t, n_motions) and the members
``familiarity_edges`` (B,), ``familiarity_quantiles`` (K, B, L) and
``familiarity_counts`` (K, B).

Optional: a ``session`` object in the metadata, what a recording session taught
besides the model (e.g. the meeting geometry, :mod:`sandbox.data.geometry`),
kept as :attr:`IProMP.session` and never interpreted here; files without it load
with an empty one.

Version history: 1 (package 0.1.0) had the hand only (``human_names``, no
modalities, no scale); such files still load, as one position modality
``"hand"``. Version 2 adds the modalities, the scale and the floors. The
familiarity section is optional within version 2: files without it load with
``calibration = None`` (the predictors' familiarity is then None, never
computed lazily: calibrating needs the training streams), and readers that
predate it ignore it.

Loading trusts nothing in the file (:mod:`sandbox.core.archive`): the file's
size and number of members are checked first; the metadata is read and
checked (types, ranges, the priors a probability vector, the speed priors
positive, durations within :data:`~sandbox.core.limits.MAX_TIME_S`) before any
array; only the members it declares are read, each after its ``.npy`` header
declared the dtype and shape the metadata implies, within the limits; every
array must be finite, within :data:`~sandbox.core.limits.MAX_MODEL_VALUE`, the
noise, scale and regularisers positive (so every weight covariance
:math:`UU^T + \\Lambda` is symmetric positive definite; the robot's regulariser
at least half :data:`~sandbox.core.limits.MIN_REGULARIZER` of its weights'
variance, so it stays so in floating point). A corrupt, truncated,
tampered or foreign file, or one from another format version, is refused with
one ``ValueError`` that says which file and why, and never suggests pickle.
"""

from __future__ import annotations

import json
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from sandbox.core.archive import ArchiveError, check_path, open_archive, read_array
from sandbox.core.basis import GaussianBasis
from sandbox.core.limits import (
    MAX_ALPHA_STD,
    MAX_DIMS,
    MAX_METADATA_BYTES,
    MAX_MODEL_VALUE,
    MAX_TASKS,
    MAX_TIME_S,
    MIN_ALPHA_STD,
    MIN_MEDIAN_DT_S,
    MIN_NOISE_STD,
)
from sandbox.core.modality import Modality, check_modalities, default_modalities
from sandbox.core.promp import (
    WeightDistribution,
    check_human_conditioning,
    check_robot_definite,
)
from sandbox.validation import check_number

if TYPE_CHECKING:
    from sandbox.core.model import IProMP

if TYPE_CHECKING:
    from sandbox.core.calibration import Calibration

FORMAT = "handover-sandbox/iprompt"
FORMAT_VERSION = 2
READABLE_VERSIONS = (1, 2)
#: Hyperparameters each format version stores (the IProMP options).
HYPERPARAMETERS = {
    1: {"regularizer", "noise_scale", "noise_floor", "min_alpha_std", "ridge"},
    2: {"regularizer", "noise_scale", "noise_floor", "signal_floor", "noise_floors",
        "settle_tol", "arrive_tol", "min_alpha_std", "ridge"},
}
TASK_KEYS = {"name", "nominal_duration", "alpha_mean", "alpha_std", "n_demos", "prior"}
#: Most time bins of a stored familiarity calibration.
MAX_TIME_BINS = 1000
#: How far from 1 the stored priors may sum.
PRIOR_TOLERANCE = 1e-6
#: How far from 1 a stored ``alpha_mean`` may be (a fit writes exactly 1).
ALPHA_MEAN_TOLERANCE = 1e-9


def save_model(model: IProMP, path: str | os.PathLike) -> None:
    """Write a fitted :class:`~sandbox.core.model.IProMP` to ``path`` (``.npz``)."""
    meta = {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "basis": model.basis.to_dict(),
        "hyperparameters": {
            "regularizer": model.regularizer,
            "noise_scale": model.noise_scale,
            "noise_floor": model.noise_floor,
            "signal_floor": model.signal_floor,
            "noise_floors": dict(model.noise_floors),
            "settle_tol": model.settle_tol,
            "arrive_tol": model.arrive_tol,
            "min_alpha_std": model.min_alpha_std,
            "ridge": model.ridge,
        },
        "n_human": model.n_human,
        "n_robot": model.n_robot,
        "modalities": [m.to_dict() for m in model.modalities],
        "robot_names": list(model.robot_names),
        "tasks": [
            {
                "name": t.name,
                "nominal_duration": t.nominal_duration,
                "alpha_mean": t.alpha_mean,
                "alpha_std": t.alpha_std,
                "n_demos": t.n_demos,
                "prior": float(p),
            }
            for t, p in zip(model.task_models, model.priors)
        ],
    }
    arrays = {"noise": model.noise, "scale": model.scale}
    cal = getattr(model, "calibration", None)
    if cal is not None:
        meta["familiarity"] = {"threshold": cal.threshold, "alpha": cal.alpha,
                               "likelihood": cal.likelihood, "subsample": cal.subsample,
                               "dow_t": cal.dow_t, "n_motions": cal.n_motions}
        arrays.update(familiarity_edges=cal.edges, familiarity_quantiles=cal.quantiles,
                      familiarity_counts=cal.counts)
    if getattr(model, "session", None):
        meta["session"] = model.session     # kept, not interpreted (e.g. the meeting geometry)
    arrays["metadata"] = np.array(json.dumps(meta))
    for i, t in enumerate(model.task_models):
        arrays[f"task{i}_mean"] = t.weights.mean
        arrays[f"task{i}_factor"] = t.weights.factor
        arrays[f"task{i}_reg"] = t.weights.reg
    path = _output_path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            np.savez(fh, **arrays)
        os.replace(tmp, path)             # never a half-written model file
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def _output_path(path) -> Path:
    if not isinstance(path, (str, os.PathLike)):
        raise ValueError(f"path: expected a file path (str or os.PathLike), got "
                         f"{type(path).__name__}")
    path = Path(path)
    if path.is_dir():
        raise ValueError(f"path: expected a file to write, got the folder {str(path)!r}")
    if not path.parent.is_dir():
        raise ValueError(f"path: the folder {str(path.parent)!r} does not exist")
    return path


@dataclass(frozen=True, eq=False)
class ModelFile:
    """The checked content of a model file, from which
    :meth:`IProMP.load <sandbox.core.model.IProMP.load>` builds the model.

    This module knows the file format and nothing of the model class
    (:mod:`sandbox.core.model` imports this module, never the reverse).

    Attributes
    ----------
    meta : dict
        The checked metadata: ``format_version``, ``basis`` (a
        :meth:`GaussianBasis.to_dict <sandbox.core.basis.GaussianBasis.to_dict>`),
        ``hyperparameters``, ``n_human`` P, ``n_robot`` Q, ``modalities`` (tuple of
        :class:`~sandbox.core.modality.Modality`), ``robot_names``, ``tasks``
        (name, nominal_duration, alpha_mean, alpha_std, n_demos, prior per task).
    weights : tuple of WeightDistribution
        Each task's weights over P + Q dims, in the order of ``meta["tasks"]``.
    noise, scale : ndarray, shape (P,)
        Observation noise variances and the scale of every human dim.
    calibration : Calibration or None
        The familiarity calibration (:mod:`sandbox.core.familiarity`), if stored.
    """

    meta: dict
    weights: tuple[WeightDistribution, ...]
    noise: np.ndarray
    scale: np.ndarray
    calibration: Calibration | None


def read_model(path: str | os.PathLike) -> ModelFile:
    """Read and check a file written by :func:`save_model` (format version 1 or 2).

    Raises
    ------
    ValueError
        If ``path`` is not an existing file, or the file is not a valid model
        (module docstring): the message names the file and the problem.
    """
    path = check_path(path)
    try:
        return _read_model(path)
    except ValueError as error:       # ArchiveError, or a check of the content
        text = str(error)
        where = f"model file {str(path)!r}"
        raise ValueError(text if text.startswith(where) or text.startswith(f"{str(path)!r}")
                         else f"{where}: {text}") from None


def _read_model(path: Path) -> ModelFile:
    archive = open_archive(path)
    with archive:
        meta = _metadata(archive, path)
        P, Q, N = meta["n_human"], meta["n_robot"], meta["basis"]["n_basis"]
        noise = _positive(_read(archive, "noise", (P,)), "noise", MIN_NOISE_STD**2)
        scale = (_check_scale(_read(archive, "scale", (P,)), meta["modalities"])
                 if meta["format_version"] >= 2 else np.ones(P))
        weights = []
        for i, t in enumerate(meta["tasks"]):
            D = (P + Q) * N
            dist = WeightDistribution(
                _read(archive, f"task{i}_mean", (D,)),
                _factor(archive, f"task{i}_factor", D, t["n_demos"]),
                _positive(_read(archive, f"task{i}_reg", (P + Q,)), f"task{i}_reg", 0.0), N)
            check_robot_definite(dist, P, t["name"])
            check_human_conditioning(dist, noise, t["name"])
            weights.append(dist)
        calibration = _calibration(archive, meta.get("familiarity"), len(weights))
    return ModelFile(meta, tuple(weights), noise, scale, calibration)


def _calibration(archive, entry, n_tasks: int):
    """The familiarity calibration if the file has one (checked), else None."""
    from sandbox.core.calibration import LEVELS, Calibration

    if entry is None:
        return None
    keys = {"threshold", "alpha", "likelihood", "subsample", "dow_t", "n_motions"}
    if not isinstance(entry, dict) or set(entry) != keys:
        got = sorted(map(str, entry)) if isinstance(entry, dict) else entry
        raise ValueError(f"metadata familiarity: expected the keys {sorted(keys)}, got {got!r}")
    edges = _read(archive, "familiarity_edges", (None,))
    if not 1 <= edges.size <= MAX_TIME_BINS:
        raise ValueError(f"member 'familiarity_edges': expected 1 to {MAX_TIME_BINS} bins, "
                         f"got {edges.size}")
    quantiles = _read(archive, "familiarity_quantiles", (n_tasks, edges.size, LEVELS.size))
    counts = _read(archive, "familiarity_counts", (n_tasks, edges.size))
    try:
        return Calibration(edges, quantiles, counts, **entry)
    except TypeError:
        raise ValueError(f"metadata familiarity: malformed entry {str(entry)[:80]}") from None


def _factor(archive, name: str, rows: int, n_demos: int) -> np.ndarray:
    """A task's covariance factor U, shape (rows, r): 1 <= r < n_demos, not all zero.

    A fit centres its demos' weights, so n demos give at most n - 1 directions, and
    refuses demos that do not differ, so at least one.
    """
    arr = _read(archive, name, (rows, None))
    r = arr.shape[1]
    if not 1 <= r <= n_demos - 1:
        raise ValueError(f"member {name!r}: expected a covariance factor of rank 1 to "
                         f"{n_demos - 1} (its task's {n_demos} demonstrations less one), got "
                         f"{r} columns")
    if not np.any(arr):
        raise ValueError(f"member {name!r}: expected a covariance factor with a non-zero "
                         f"entry (demos that differ), got all zeros")
    return arr


def _read(archive, name: str, shape: tuple) -> np.ndarray:
    """A float member of the expected shape, finite and within MAX_MODEL_VALUE."""
    arr = read_array(archive, name, "fiu", shape).astype(np.float64)
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"member {name!r} holds NaN or infinity")
    if arr.size and np.abs(arr).max() > MAX_MODEL_VALUE:
        raise ValueError(f"member {name!r} holds values beyond +/-{MAX_MODEL_VALUE:g} "
                         f"(limits.MAX_MODEL_VALUE)")
    return arr


def _check_scale(scale: np.ndarray, modalities) -> np.ndarray:
    """1 for position dims (never normalised), at least MIN_NOISE_STD for signal dims."""
    position = np.array([m.kind == "position" for m in modalities for _ in m.dims])
    if np.any(scale[position] != 1.0) or np.any(scale[~position] < MIN_NOISE_STD):
        raise ValueError(f"scale must be 1 for position dims and at least {MIN_NOISE_STD:g} "
                         f"for signal dims, got {scale.tolist()}")
    return scale


def _positive(arr: np.ndarray, name: str, low: float) -> np.ndarray:
    if np.any(arr <= low):
        raise ValueError(f"{name} must be {arr.size} positive numbers"
                         + (f" of at least {low:g}" if low else "") + f", got {arr.min():g}")
    return arr


def _metadata(archive, path: Path) -> dict:
    """The metadata, checked: every field of the expected type and range."""
    if "metadata.npy" not in archive.namelist():
        raise ArchiveError(f"{str(path)!r} is not a handover-sandbox model (no metadata entry)")
    text = read_array(archive, "metadata", "U", (), MAX_METADATA_BYTES)
    try:
        meta = json.loads(str(text))
    except (ValueError, RecursionError):
        raise ValueError("metadata is not valid JSON") from None
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
            "tasks": _tasks(meta["tasks"], _min_alpha_std(meta["hyperparameters"])),
            "familiarity": meta.get("familiarity"),
            "session": _session(meta.get("session", {}))}


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
        return check_number(value, "", low=MIN_ALPHA_STD, high=MAX_ALPHA_STD)
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
