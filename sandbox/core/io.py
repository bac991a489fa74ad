"""Saving and loading fitted models: ``.npz`` arrays + JSON metadata, never pickle.

Layout of the file (a numpy ``.npz`` archive, written atomically; any reader of
``.npz`` can open it with ``allow_pickle=False``):

* ``metadata``: a 0-d unicode array holding JSON with ``format`` (= :data:`FORMAT`),
  ``format_version`` (= :data:`FORMAT_VERSION`), the basis, the hyperparameters, the
  modalities (name, dims, kind, units), names of the robot dims, per-task durations and priors;
* ``noise``: :math:`\\sigma_p^2` (normalised units), shape (P,);
* ``scale``: the scale of every human dim (signal normaliser; 1 for positions), shape (P,);
* for task i: ``task{i}_mean`` (D*N,), ``task{i}_factor`` (D*N, r), ``task{i}_reg`` (D,).

Optional, for a model with a familiarity calibration
(:mod:`sandbox.core.familiarity`): a ``familiarity`` entry in the metadata
(threshold, alpha, likelihood, subsample, dow_t, n_motions, ``components`` when more than
the Mahalanobis term is ranked, ``end_prob`` when gated to the ongoing motion) and the members
``familiarity_edges`` (B,), ``familiarity_quantiles`` (K, B, L), ``familiarity_counts``
(K, B), and ``familiarity_extra`` (J - 1, K, B, L) with ``components``; without
``components`` (before the timing evidence), a calibration of the Mahalanobis term; without
``end_prob``, one of every update; ``motion`` (2, n), the calibration motions' lowest answer
to each question (:mod:`sandbox.core.questions`; without it, compared as they are);
``cells`` ("own" or "chosen", :mod:`sandbox.core.cells`), how the cells were filed (without
it, unknown: ``Calibration.cells`` None; the quantiles rank the same either way).

Optional: a ``session`` object in the metadata (e.g. the meeting geometry,
:mod:`sandbox.data.geometry`), kept as :attr:`IProMP.session`, never interpreted here.
``span_reg`` (:mod:`sandbox.core.spanreg`, null too) and, when set, ``span_used`` (per
modality its out-of-span variance and factor); files before it load without and say so.
``post_end`` and ``post_var`` (:mod:`sandbox.core.posthold`), only when set.

Version history: 1 (package 0.1.0) had the hand only (``human_names``, no modalities, no
scale); such files still load, as one position modality ``"hand"``. Version 2 adds the
modalities, the scale and the floors. Files without the optional familiarity section load
with ``calibration = None`` (never computed lazily); readers that predate it ignore it.

Loading trusts nothing in the file (:mod:`sandbox.core.archive`): the file's size and
number of members are checked first; the metadata is read and checked
(:mod:`sandbox.core.modelmeta`: types, ranges, the priors a probability vector, the speed
priors as a fit makes them, durations within :data:`~sandbox.core.limits.MAX_TIME_S`)
before any array; only the members it declares are read, each after its ``.npy`` header
declared the dtype and shape the metadata implies, within the limits; every array must be
finite, within :data:`~sandbox.core.limits.MAX_MODEL_VALUE`, each task's covariance factor
of rank 1 to n_demos - 1, the human regularisers at most
:data:`~sandbox.core.limits.MAX_KAPPA` times the noise, the noise, scale and regularisers
positive (so every weight covariance :math:`UU^T + \\Lambda` is symmetric positive definite;
the robot's regulariser at least half :data:`~sandbox.core.limits.MIN_REGULARIZER` of its
weights' variance, so it stays so in floating point). A corrupt, truncated, tampered or
foreign file, or one from another format version, is refused with one ``ValueError`` that
says which file and why, and never suggests pickle.
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
from sandbox.core.fileoptions import put_options
from sandbox.core.limits import MAX_METADATA_BYTES, MAX_MODEL_VALUE, MIN_NOISE_STD
from sandbox.core.modelmeta import (  # noqa: F401 - the format's constants, re-exported
    FORMAT,
    FORMAT_VERSION,
    HYPERPARAMETERS,
    READABLE_VERSIONS,
    check_metadata,
)
from sandbox.core.promp import WeightDistribution, check_human_conditioning, check_robot_definite
from sandbox.core.spanreg import SPAN_NOTE

if TYPE_CHECKING:
    from sandbox.core.calibration import Calibration
    from sandbox.core.model import IProMP

#: Most time bins of a stored familiarity calibration.
MAX_TIME_BINS = 1000
#: Most statistics a stored familiarity calibration ranks.
MAX_COMPONENTS = 16


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
        "robot_space": getattr(model, "robot_space", "joint"),
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
    put_options(model, meta)
    arrays = {"noise": model.noise, "scale": model.scale}
    _put_calibration(getattr(model, "calibration", None), meta, arrays)
    if getattr(model, "session", None):
        meta["session"] = model.session     # kept, not interpreted (e.g. the meeting geometry)
    arrays["metadata"] = np.array(json.dumps(meta))
    for i, t in enumerate(model.task_models):
        arrays[f"task{i}_mean"] = t.weights.mean
        arrays[f"task{i}_factor"] = t.weights.factor
        arrays[f"task{i}_reg"] = t.weights.reg
        if t.robot is not None:                  # shrinkage="robot": same mean and reg
            arrays[f"task{i}_robot_factor"] = t.robot.factor
    path = _output_path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            np.savez(fh, **arrays)
        os.replace(tmp, path)             # never a half-written model file
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def _put_calibration(cal, meta: dict, arrays: dict) -> None:
    """Add a familiarity calibration (if any) to the file's metadata and arrays, in place."""
    if cal is None:
        return
    meta["familiarity"] = {"threshold": cal.threshold, "alpha": cal.alpha,
                           "likelihood": cal.likelihood, "subsample": cal.subsample,
                           "dow_t": cal.dow_t, "n_motions": cal.n_motions}
    arrays.update(familiarity_edges=cal.edges, familiarity_quantiles=cal.quantiles,
                  familiarity_counts=cal.counts)
    if cal.extra is not None:
        meta["familiarity"]["components"] = list(cal.components)
        arrays["familiarity_extra"] = cal.extra
    if cal.end_prob is not None:
        meta["familiarity"]["end_prob"] = cal.end_prob
    if cal.motion is not None:
        meta["familiarity"]["motion"] = np.asarray(cal.motion, dtype=float).tolist()
    if cal.cells is not None:
        meta["familiarity"]["cells"] = cal.cells


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
    robot : tuple of WeightDistribution or None
        With ``shrinkage="robot"``, each task's weights that condition the robot
        (:attr:`~sandbox.core.fitting.TaskModel.robot`); else None.
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
    robot: tuple[WeightDistribution, ...] | None = None


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
        shrunk = meta["hyperparameters"].get("shrinkage", "none") != "none"
        pooled_rank = sum(t["n_demos"] for t in meta["tasks"]) - len(meta["tasks"])
        for i, t in enumerate(meta["tasks"]):
            D = (P + Q) * N
            dist = WeightDistribution(
                _read(archive, f"task{i}_mean", (D,)),
                _factor(archive, f"task{i}_factor", D, t["n_demos"],
                        pooled_rank if shrunk else None),
                _positive(_read(archive, f"task{i}_reg", (P + Q,)), f"task{i}_reg", 0.0), N)
            check_robot_definite(dist, P, t["name"])
            check_human_conditioning(dist, noise, t["name"])
            weights.append(dist)
        robot = None
        if meta["hyperparameters"].get("shrinkage") == "robot":
            robot = tuple(WeightDistribution(w.mean, _factor(
                archive, f"task{i}_robot_factor", w.mean.size, t["n_demos"], pooled_rank),
                w.reg, N) for i, (t, w) in enumerate(zip(meta["tasks"], weights)))
        calibration = _calibration(archive, meta.get("familiarity"), len(weights))
    return ModelFile(meta, tuple(weights), noise, scale, calibration, robot)


def _calibration(archive, entry, n_tasks: int):
    """The familiarity calibration if the file has one (checked), else None."""
    from sandbox.core.calibration import LEVELS, Calibration
    from sandbox.core.cells import CELLS

    if entry is None:
        return None
    keys = {"threshold", "alpha", "likelihood", "subsample", "dow_t", "n_motions"}
    optional = {"components", "end_prob", "motion", "cells"}
    if not isinstance(entry, dict) or set(entry) - optional != keys:
        got = sorted(map(str, entry)) if isinstance(entry, dict) else entry
        raise ValueError(f"metadata familiarity: expected the keys {sorted(keys)}, got {got!r}")
    edges = _read(archive, "familiarity_edges", (None,))
    if not 1 <= edges.size <= MAX_TIME_BINS:
        raise ValueError(f"member 'familiarity_edges': expected 1 to {MAX_TIME_BINS} bins, "
                         f"got {edges.size}")
    quantiles = _read(archive, "familiarity_quantiles", (n_tasks, edges.size, LEVELS.size))
    counts = _read(archive, "familiarity_counts", (n_tasks, edges.size))
    entry = dict(entry)
    if entry.get("cells", "own") not in CELLS:
        raise ValueError(f"metadata familiarity cells: expected one of {list(CELLS)}, got "
                         f"{str(entry['cells'])[:80]}")
    names = entry.pop("components", ["mahalanobis"])
    if not isinstance(names, list) or not 1 <= len(names) <= MAX_COMPONENTS:
        raise ValueError(f"metadata familiarity components: expected a list of 1 to "
                         f"{MAX_COMPONENTS} names, got {str(names)[:80]}")
    extra = (_read(archive, "familiarity_extra", (len(names) - 1, n_tasks, edges.size,
                                                  LEVELS.size)) if len(names) > 1 else None)
    try:
        return Calibration(edges, quantiles, counts, **entry, components=tuple(names),
                           extra=extra)
    except TypeError:
        raise ValueError(f"metadata familiarity: malformed entry {str(entry)[:80]}") from None


def _factor(archive, name: str, rows: int, n_demos: int,
            pooled_rank: int | None = None) -> np.ndarray:
    """A task's covariance factor U, shape (rows, r): 1 <= r < n_demos, not all zero.

    A fit centres its demos' weights, so n demos give at most n - 1 directions, and
    refuses demos that do not differ, so at least one. A covariance shrunk toward the
    pooled one (:mod:`sandbox.core.shrinkage`) has ``pooled_rank`` more (all demos
    less the number of tasks).
    """
    arr = _read(archive, name, (rows, None))
    r = arr.shape[1]
    most = n_demos - 1 + (pooled_rank or 0)
    if not 1 <= r <= most:
        held = (f"its task's {n_demos} demonstrations less one" if pooled_rank is None else
                "its task's demonstrations less one, and all tasks' less the number of tasks")
        raise ValueError(f"member {name!r}: expected a covariance factor of rank 1 to "
                         f"{most} ({held}), got {r} columns")
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
    return check_metadata(meta, path)


def model_from_file(cls, f: ModelFile):
    """The fitted model (an instance of ``cls``, :class:`~sandbox.core.model.IProMP`) a
    checked :class:`ModelFile` describes."""
    from sandbox.core.fitting import TaskModel

    meta = f.meta
    v1: dict[str, Any] = ({"settle_tol": None, "arrive_tol": None}
                          if meta["format_version"] == 1 else {})
    basis = meta["basis"]
    model = cls(n_basis=basis["n_basis"], basis_width=basis["width"],
                basis_margin=basis["margin"], normalized_basis=basis["normalized"], **v1,
                **{"jitter_floor": None, **meta["hyperparameters"]})   # older files: none
    model.task_models = tuple(
        TaskModel(t["name"], w, t["nominal_duration"], t["alpha_mean"], t["alpha_std"],
                  t["n_demos"], None if f.robot is None else f.robot[i])
        for i, (t, w) in enumerate(zip(meta["tasks"], f.weights)))
    model.noise = f.noise
    model.scale = f.scale
    model.modalities = meta["modalities"]
    model.n_human, model.n_robot = meta["n_human"], meta["n_robot"]
    model.human_names = tuple(d for m in meta["modalities"] for d in m.dims)
    model.robot_names = tuple(meta["robot_names"])
    model.robot_space = meta["robot_space"]
    model.priors = np.array([t["prior"] for t in meta["tasks"]], dtype=np.float64)
    model.calibration = f.calibration
    model.session = dict(meta["session"])
    if meta.get("floors_used") is not None:
        model.floors_used = np.asarray(meta["floors_used"], dtype=np.float64)
    if meta.get("condition_noise") is not None:     # files before it condition with noise
        model.condition_noise = np.asarray(meta["condition_noise"], dtype=np.float64)
    model.condition_floor = meta["hyperparameters"].get("condition_floor")
    model.span_report = dict(meta.get("span_used") or {})
    model.span_note = None if "span_reg" in meta["hyperparameters"] else SPAN_NOTE
    model.post_var = None if meta["post_var"] is None else np.asarray(meta["post_var"], float)
    model._fitted = True
    return model
