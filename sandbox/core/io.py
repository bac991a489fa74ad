"""Saving and loading fitted models: ``.npz`` arrays + JSON metadata, never pickle.

Layout of the file (a numpy ``.npz`` archive, loaded with ``allow_pickle=False``):

* ``metadata``: a 0-d unicode array holding JSON with ``format`` (=
  :data:`FORMAT`), ``format_version`` (= :data:`FORMAT_VERSION`), the basis,
  the hyperparameters, the modalities (name, dims, kind, units), names of the
  robot dims, per-task durations and priors;
* ``noise``: :math:`\\sigma_p^2` (normalised units), shape (P,);
* ``scale``: the scale of every human dim (signal normaliser; 1 for positions), shape (P,);
* for task i: ``task{i}_mean`` (D*N,), ``task{i}_factor`` (D*N, r), ``task{i}_reg`` (D,).

Version history: 1 (package 0.1.0) had the hand only (``human_names``, no
modalities, no scale); such files still load, as one position modality
``"hand"``. Version 2 adds the modalities, the scale and the floors.

The metadata is read and checked before any array, and only the members it
declares are read. A corrupt, truncated or foreign file, or one from another
format version, is refused with a ``ValueError`` that says which and why.
"""

from __future__ import annotations

import json
import os
import zipfile
from pathlib import Path

import numpy as np

from sandbox.core.basis import GaussianBasis
from sandbox.core.modality import Modality, check_modalities, default_modalities
from sandbox.core.promp import WeightDistribution

FORMAT = "handover-sandbox/iprompt"
FORMAT_VERSION = 2
READABLE_VERSIONS = (1, 2)


def save_model(model, path: str | os.PathLike) -> None:
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
    arrays = {"metadata": np.array(json.dumps(meta)), "noise": model.noise, "scale": model.scale}
    for i, t in enumerate(model.task_models):
        arrays[f"task{i}_mean"] = t.weights.mean
        arrays[f"task{i}_factor"] = t.weights.factor
        arrays[f"task{i}_reg"] = t.weights.reg
    path = Path(path)
    with open(path, "wb") as fh:
        np.savez(fh, **arrays)


def load_model(path: str | os.PathLike):
    """Read a model written by :func:`save_model` (format version 1 or 2)."""
    from sandbox.core.model import IProMP, TaskModel

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"model file: expected an existing .npz file, got {str(path)!r}")
    try:
        data = np.load(path, allow_pickle=False)
    except (zipfile.BadZipFile, OSError, EOFError, ValueError) as error:
        raise _corrupt(path, error) from error
    if not isinstance(data, np.lib.npyio.NpzFile):
        raise ValueError(f"{str(path)!r} is not a handover-sandbox model (a bare array, "
                         f"not an .npz archive)")
    with data:
        meta = _metadata(data, path)
        names = ["noise"] + (["scale"] if meta["format_version"] >= 2 else [])
        names += [f"task{i}_{part}" for i in range(len(meta["tasks"]))
                  for part in ("mean", "factor", "reg")]
        missing = [n for n in names if n not in data.files]
        if missing:
            raise ValueError(f"model file {str(path)!r} is inconsistent: lacks {missing}")
        arrays = {k: _member(data, k, path) for k in names}
    hyper = dict(meta["hyperparameters"])
    model = IProMP(
        basis_width=meta["basis"]["width"],
        n_basis=meta["basis"]["n_basis"],
        basis_margin=meta["basis"]["margin"],
        normalized_basis=meta["basis"]["normalized"],
        **({"settle_tol": None, "arrive_tol": None} if meta["format_version"] == 1 else {}),
        **hyper,
    )
    tasks = []
    try:
        for i, t in enumerate(meta["tasks"]):
            dist = WeightDistribution(
                arrays[f"task{i}_mean"], arrays[f"task{i}_factor"], arrays[f"task{i}_reg"],
                meta["basis"]["n_basis"],
            )
            tasks.append(TaskModel(t["name"], dist, float(t["nominal_duration"]),
                                   float(t["alpha_mean"]), float(t["alpha_std"]),
                                   int(t["n_demos"])))
        noise = np.asarray(arrays["noise"], dtype=np.float64)
        P = int(meta["n_human"])
        scale = np.asarray(arrays.get("scale", np.ones(P)), dtype=np.float64)
        modalities = _modalities(meta, P)
    except (KeyError, TypeError, ValueError) as error:
        raise ValueError(f"model file {str(path)!r} is inconsistent: {error}") from error
    _check_consistent(meta, tasks, noise, scale, path)
    model.task_models = tuple(tasks)
    model.noise = noise
    model.scale = scale
    model.modalities = modalities
    model.n_human, model.n_robot = P, int(meta["n_robot"])
    model.human_names = tuple(d for m in modalities for d in m.dims)
    model.robot_names = tuple(meta["robot_names"])
    model.priors = np.array([float(t["prior"]) for t in meta["tasks"]])
    model._fitted = True
    return model


def _corrupt(path: Path, error: Exception) -> ValueError:
    return ValueError(f"model file {str(path)!r} is corrupt, truncated or not a .npz archive "
                      f"({type(error).__name__})")


def _member(data, name: str, path: Path) -> np.ndarray:
    try:
        return data[name]
    except (zipfile.BadZipFile, OSError, EOFError, ValueError, KeyError) as error:
        raise _corrupt(path, error) from error


def _modalities(meta: dict, P: int) -> tuple:
    if meta["format_version"] == 1:
        names = tuple(meta.get("human_names") or ()) or tuple(f"human_{i}" for i in range(P))
        return check_modalities(default_modalities(names), P)
    return check_modalities([Modality.from_dict(m) for m in meta["modalities"]], P)


def _metadata(data, path: Path) -> dict:
    if "metadata" not in data.files:
        raise ValueError(f"{str(path)!r} is not a handover-sandbox model (no metadata entry)")
    try:
        meta = json.loads(str(_member(data, "metadata", path)))
    except (json.JSONDecodeError, RecursionError) as error:
        raise ValueError(f"model file {str(path)!r}: metadata is not valid JSON") from error
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        got = meta.get("format") if isinstance(meta, dict) else type(meta).__name__
        raise ValueError(f"{str(path)!r} is not a handover-sandbox model (format {got!r})")
    if meta.get("format_version") not in READABLE_VERSIONS:
        raise ValueError(
            f"model file {str(path)!r} has format version {meta.get('format_version')!r}; "
            f"this version of the package reads versions {list(READABLE_VERSIONS)}"
        )
    need = ["basis", "hyperparameters", "n_human", "n_robot", "tasks", "robot_names"]
    need += ["modalities"] if meta["format_version"] >= 2 else []
    for key in need:
        if key not in meta:
            raise ValueError(f"model file {str(path)!r}: metadata lacks {key!r}")
    GaussianBasis.from_dict(meta["basis"])
    return meta


def _check_consistent(meta: dict, tasks, noise, scale, path: Path) -> None:
    P, Q = int(meta["n_human"]), int(meta["n_robot"])
    if noise.shape != (P,) or not np.all(np.isfinite(noise)) or np.any(noise <= 0):
        raise ValueError(f"model file {str(path)!r}: noise must be {P} positive numbers")
    if scale.shape != (P,) or not np.all(np.isfinite(scale)) or np.any(scale <= 0):
        raise ValueError(f"model file {str(path)!r}: scale must be {P} positive numbers")
    for t in tasks:
        if t.weights.n_dims != P + Q:
            raise ValueError(
                f"model file {str(path)!r}: task {t.name!r} has {t.weights.n_dims} dims, "
                f"expected P+Q={P + Q}"
            )
        if not (np.isfinite(t.weights.factor).all() and t.nominal_duration > 0 and t.alpha_std > 0):
            raise ValueError(f"model file {str(path)!r}: task {t.name!r} has invalid numbers")
    if not tasks:
        raise ValueError(f"model file {str(path)!r}: no tasks")
