"""Saving and loading fitted models: ``.npz`` arrays + JSON metadata, never pickle.

Layout of the file (a numpy ``.npz`` archive, loaded with ``allow_pickle=False``):

* ``metadata``: a 0-d unicode array holding JSON with ``format`` (=
  :data:`FORMAT`), ``format_version`` (= :data:`FORMAT_VERSION`), the basis,
  the hyperparameters, names of dims and tasks, per-task durations and priors;
* ``noise``: :math:`\\sigma_p^2`, shape (P,);
* for task i: ``task{i}_mean`` (D*N,), ``task{i}_factor`` (D*N, r), ``task{i}_reg`` (D,).

A corrupt, truncated or foreign file, or one from another format version, is
refused with a ``ValueError`` that says which and why.
"""

from __future__ import annotations

import json
import os
import zipfile
from pathlib import Path

import numpy as np

from sandbox.core.basis import GaussianBasis
from sandbox.core.promp import WeightDistribution

FORMAT = "handover-sandbox/iprompt"
FORMAT_VERSION = 1


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
            "min_alpha_std": model.min_alpha_std,
            "ridge": model.ridge,
        },
        "n_human": model.n_human,
        "n_robot": model.n_robot,
        "human_names": list(model.human_names),
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
    arrays = {"metadata": np.array(json.dumps(meta)), "noise": model.noise}
    for i, t in enumerate(model.task_models):
        arrays[f"task{i}_mean"] = t.weights.mean
        arrays[f"task{i}_factor"] = t.weights.factor
        arrays[f"task{i}_reg"] = t.weights.reg
    path = Path(path)
    with open(path, "wb") as fh:
        np.savez(fh, **arrays)


def load_model(path: str | os.PathLike):
    """Read a model written by :func:`save_model`."""
    from sandbox.core.model import IProMP, TaskModel

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"model file: expected an existing .npz file, got {str(path)!r}")
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {k: data[k] for k in data.files}
    except (zipfile.BadZipFile, OSError, EOFError, ValueError, KeyError) as error:
        raise ValueError(
            f"model file {str(path)!r} is corrupt, truncated or not a .npz archive ({error})"
        ) from error
    meta = _metadata(arrays, path)
    model = IProMP(
        basis_width=meta["basis"]["width"],
        n_basis=meta["basis"]["n_basis"],
        basis_margin=meta["basis"]["margin"],
        normalized_basis=meta["basis"]["normalized"],
        **meta["hyperparameters"],
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
    except (KeyError, TypeError, ValueError) as error:
        raise ValueError(f"model file {str(path)!r} is inconsistent: {error}") from error
    _check_consistent(meta, tasks, noise, path)
    model.task_models = tuple(tasks)
    model.noise = noise
    model.n_human, model.n_robot = int(meta["n_human"]), int(meta["n_robot"])
    model.human_names = tuple(meta["human_names"])
    model.robot_names = tuple(meta["robot_names"])
    model.priors = np.array([float(t["prior"]) for t in meta["tasks"]])
    model._fitted = True
    return model


def _metadata(arrays: dict, path: Path) -> dict:
    if "metadata" not in arrays:
        raise ValueError(f"{str(path)!r} is not a handover-sandbox model (no metadata entry)")
    try:
        meta = json.loads(str(arrays["metadata"]))
    except json.JSONDecodeError as error:
        raise ValueError(f"model file {str(path)!r}: metadata is not valid JSON") from error
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        got = meta.get("format") if isinstance(meta, dict) else type(meta).__name__
        raise ValueError(f"{str(path)!r} is not a handover-sandbox model (format {got!r})")
    if meta.get("format_version") != FORMAT_VERSION:
        raise ValueError(
            f"model file {str(path)!r} has format version {meta.get('format_version')!r}; "
            f"this version of the package reads version {FORMAT_VERSION}"
        )
    for key in ("basis", "hyperparameters", "n_human", "n_robot", "tasks"):
        if key not in meta:
            raise ValueError(f"model file {str(path)!r}: metadata lacks {key!r}")
    GaussianBasis.from_dict(meta["basis"])
    return meta


def _check_consistent(meta: dict, tasks, noise, path: Path) -> None:
    P, Q = int(meta["n_human"]), int(meta["n_robot"])
    if noise.shape != (P,) or not np.all(np.isfinite(noise)) or np.any(noise <= 0):
        raise ValueError(f"model file {str(path)!r}: noise must be {P} positive numbers")
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
