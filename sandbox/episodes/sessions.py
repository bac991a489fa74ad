"""Synthetic recording sessions as episodes: a model fitted on one session, replayed in another.

A synthetic session (:func:`sandbox.data.synthetic.draw_session`) draws what a
recording session of a lab would fix: the tracker's frame (offset, rotation),
where the fingertip meets the object, the tempo, and what the hand does after
the handover (its tail). :func:`session_episodes` makes the episodes of the
``diverging`` and ``objects`` scenarios for one:

* the model is fitted on ``n_per_task`` demonstrations of the *training*
  session (default: the replayed one), with their meeting geometry
  (:mod:`sandbox.data.geometry`), and the object rides where that model says
  the fingertip meets the hand (the ``grasp_offset`` reset option);
* each episode's hand motion is drawn from ``seed + i`` in the replayed
  session (:func:`sandbox.envs.sources.synthetic_motion`) and given to the
  environment as its scripted ``motion``, so every policy sees the same ones;
* the held-out demonstration of each episode is the one its motion comes from,
  so the ``recorded_robot`` policy replays the robot that met that hand (the
  oracle: the motion a perfect predictor would produce).

Examples
--------
>>> from sandbox.episodes.scenarios import run_scenario, summarize
>>> results = run_scenario("diverging", "recorded_robot", n_episodes=2, session=3)
>>> summarize(results)["success_rate"]
1.0
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from types import SimpleNamespace
from typing import Any

import numpy as np

from sandbox.validation import check_integer

#: Demonstrations per task a session's model is fitted on (as :func:`fit_family_model`).
N_PER_TASK = 20


def check_session(value: Any, name: str = "session") -> int | None:
    """``value`` as a session seed (an integer >= 0) or None."""
    return None if value is None else check_integer(value, name, 0)


def fit_session_model(family: str, session: int, observe=("hand",), *,
                      n_per_task: int = N_PER_TASK, seed: int = 0):
    """An IProMP (with its meeting geometry) fitted on a synthetic session's demonstrations.

    Cached per arguments: do not modify the model.
    """
    names = tuple(n.strip() for n in observe.split(",")) if isinstance(observe, str) \
        else tuple(observe)
    return fit_synthetic(family, check_integer(n_per_task, "n_per_task", 2), int(seed), None,
                         names, check_integer(session, "session", 0))


@functools.lru_cache(maxsize=8)
def fit_synthetic(family: str, n_per_task: int, seed: int, n_basis: int | None,
                  observe: tuple[str, ...], session: int | None = None, shrinkage: str = "none"):
    """An IProMP (default options but ``n_basis`` and ``shrinkage``) fitted on a synthetic
    family's demos of ``session`` (None: sessionless), with their meeting geometry; cached,
    do not modify."""
    from sandbox.core import IProMP
    from sandbox.data.geometry import attach_geometry
    from sandbox.data.synthetic import make_dataset

    # Any: a Demonstration is frozen, the core's DemonstrationLike declares plain attributes
    demos: list[Any] = make_dataset(family, n_per_task, np.random.default_rng(seed),
                                    observe=observe, session=session)
    from sandbox.episodes.libraries import remember_demos

    model = IProMP(shrinkage=shrinkage) if n_basis is None else IProMP(n_basis=n_basis,
                                                                       shrinkage=shrinkage)
    return remember_demos(attach_geometry(model.fit(demos), demos), demos)


#: Fresh motions per task a default model's familiarity is calibrated on (split-conformal:
#: a draw of the family the model was not fitted on, streamed as a predictor receives it).
N_CALIBRATION = 10
#: Entropy added to a model's seed for its calibration draw (independent of the demos and
#: of the episodes, which use ``seed + i``).
CALIBRATION_STREAM = 27


@functools.lru_cache(maxsize=8)
def calibrated_synthetic(family: str, n_per_task: int, seed: int, n_basis: int | None,
                         observe: tuple[str, ...], session: int | None = None,
                         shrinkage: str = "none"):
    """:func:`fit_synthetic`'s model with its familiarity calibrated (issue 27: the default
    models' "unsure / unknown motion" warning); cached, do not modify.

    The calibration motions are :data:`N_CALIBRATION` fresh ones per task of the same
    family and session (``np.random.default_rng([seed, CALIBRATION_STREAM])``),
    causally preprocessed as a predictor receives them, and streamed by the model
    itself (``refit=False``: they are not its training demos).
    """
    import copy

    from sandbox.data.preprocess import preprocess_demonstration
    from sandbox.data.synthetic import make_dataset

    more = {} if shrinkage == "none" else {"shrinkage": shrinkage}
    fitted = (fit_synthetic(family, n_per_task, seed, n_basis, observe, **more)
              if session is None else
              fit_synthetic(family, n_per_task, seed, n_basis, observe, session, **more))
    model = copy.copy(fitted)         # the same cache key as fit_family_model's: one fit
    rng = np.random.default_rng([seed, CALIBRATION_STREAM])
    fresh = make_dataset(family, N_CALIBRATION, rng, observe=observe, session=session)
    model.calibrate([preprocess_demonstration(d, "causal") for d in fresh], refit=False)
    return model


def session_episodes(family: str, n: int, seed: int, session: int, *,
                     train_session: int | None = None, model=None,
                     options: Mapping[str, Any] | None = None,
                     observe=None) -> list:
    """The :class:`~sandbox.episodes.replays.Replay` of ``n`` episodes of a session.

    Parameters
    ----------
    family : str
        ``"diverging"`` or ``"objects"``.
    n, seed : int
        Episode ``i`` draws its task and motion from ``np.random.default_rng(seed + i)``.
    session : int
        The session the episodes are drawn from.
    train_session : int, optional
        The session the model is fitted on (default ``session``); ignored with ``model``.
    model : IProMP, optional
        A model to use instead (the object then rides at its geometry).
    options : mapping, optional
        More reset options; ``task`` fixes every episode's task, ``speed`` is applied to
        the motion and to the replayed robot alike.
    observe : sequence of str, optional
        Modalities of the fitted model (default the hand).
    """
    from sandbox.envs.sources import family_tasks, synthetic_motion
    from sandbox.episodes.replays import Replay, grasp_options

    train = session if train_session is None else train_session
    provenance = {"mode": "synthetic-session", "session": session,
                  "train": None if model is not None else train}
    if model is None:
        model = fit_session_model(family, train, observe or ("hand",))
    opts = {k: v for k, v in (options or {}).items() if k != "task"}
    task = (options or {}).get("task")
    speed = float(opts.get("speed", 1.0))
    out = []
    for i in range(n):
        rng = np.random.default_rng(seed + i)
        name = task if task is not None else str(rng.choice(family_tasks(family)))
        motion = synthetic_motion(family, name, rng, session=session)
        robot = motion.meta["robot"]
        demo = SimpleNamespace(times=np.asarray(robot["times"]) / speed, robot=robot["joints"],
                               task=name, source=motion.source)
        out.append(Replay(seed + i, model, {**grasp_options(model), **opts, "motion": motion},
                          demo, provenance))
    return out
