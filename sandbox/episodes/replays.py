"""Recorded replays: the trial each episode replays and the model it is replayed with.

The ``recorded`` scenario of :func:`~sandbox.episodes.scenarios.run_scenario`
replays recorded trials in the environment: the human is the trial's own
recorded motion (the ``source`` reset option is the trial's set, ``task`` and
``trial`` its task and file name), the policy runs a model of every task, and
the object rides where that model's demonstrations met the hand (its learned
meeting geometry, :func:`~sandbox.data.geometry.attach_geometry`, passed as the
``grasp_offset`` reset option), never at the replayed trial's own meeting point.
Which trials are replayed and what the model is fitted on depends on the mode,
as in ``python -m sandbox evaluate``:

=========================  ===============================  ===============================
mode                       trials replayed                  model (and geometry) fitted on
=========================  ===============================  ===============================
``leave-one-out``          those of ``data`` (one set)      the set's other trials (per
                                                            episode)
``cross-session``          those of ``test`` (one set)      all trials of ``data`` (one
                                                            model; a folder of sessions
                                                            pooled)
``leave-one-session-out``  those of every session of        all the other sessions (one
                           ``data`` (a folder of sessions)  model per session, fitted once)
=========================  ===============================  ===============================

A folder of sessions is ``<root>/<session>/<task>/<trial>.csv``
(:func:`~sandbox.data.sessions.find_sessions`). Models are fitted on the
``observe`` modalities (default the hand) of the smoothed trials; a trial that
cannot provide them is left out (with a warning). Episode ``i`` resets with
``seed + i`` and replays the ``i``-th trial drawn from the replayed pool with
``numpy.random.default_rng(seed)`` (without replacement while the pool lasts,
so ``n`` equal to the pool's size replays every trial once). The trials a
model is fitted on must cover the tasks it is asked to replay.

Every episode's :class:`Replay` carries its ``provenance``: ``mode``, ``session``
(the set or session its trial comes from), ``train`` (what its model was fitted
on) and ``n_train`` (how many trials).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

LEAVE_ONE_OUT = "leave-one-out"
CROSS_SESSION = "cross-session"
LEAVE_ONE_SESSION_OUT = "leave-one-session-out"
#: The modes, as ``provenance["mode"]`` and the episodes command's ``config`` name them.
MODES = (LEAVE_ONE_OUT, CROSS_SESSION, LEAVE_ONE_SESSION_OUT)


class Replay(NamedTuple):
    """One planned episode.

    Attributes
    ----------
    seed : int
        The ``reset`` seed.
    model : IProMP
        Fitted with its meeting geometry.
    options : dict
        The ``reset`` options (``grasp_offset``, ``source``, ``task``, ``trial``, and
        the caller's).
    demo : Demonstration
        The replayed trial as loaded (its recorded robot is ``recorded_robot``'s).
    provenance : dict
        ``mode``, ``session``, ``train`` and ``n_train``.
    """

    seed: int
    model: Any
    options: dict
    demo: Any
    provenance: dict


def grasp_options(model, *, warn: bool = True, task: str | None = None) -> dict[str, Any]:
    """Reset options that place the object where ``model``'s demos met the hand.

    ``{"grasp_offset": {task: offset}}`` from the model's learned meeting geometry
    (:func:`sandbox.data.geometry.geometry_of`); with ``task`` (a scripted motion's
    label) not among the model's, the offset pooled over its tasks; ``{}`` (the
    environment's default, with a ``UserWarning`` when ``warn``) for a model without one.
    """
    from sandbox.data.geometry import geometry_of

    geometry, _ = geometry_of(model, warn=warn)
    if geometry.source == "default":
        return {}
    if task is not None and task not in geometry.tasks:
        return {"grasp_offset": geometry.pooled().tolist()}
    return {"grasp_offset": geometry.offsets()}


class _Set(NamedTuple):
    """The usable trials of one set or session and the folder the environment reads."""

    name: str
    folder: Path
    demos: list
    spec: Any = None           # a DataSpec: the environment replays motions loaded with it


def replay_mode(data: str | Path, test: str | Path | None = None, *,
                names: tuple[str, str] = ("data", "test")) -> str:
    """The mode (:data:`MODES`) of replaying ``data`` (and ``test``).

    ``ValueError`` for a ``test`` that is not one set (a folder of sessions
    included) or a ``data`` that holds both layouts; ``names`` are what the
    messages call ``data`` and ``test`` (e.g. the command's options).
    """
    from sandbox.data.sessions import SET_LAYOUT, find_sessions

    if test is not None:
        if not Path(test).is_dir():
            raise ValueError(f"{names[1]}: expected a folder {SET_LAYOUT}, got {str(test)!r}")
        if find_sessions(test, names[1]):
            raise ValueError(f"{names[1]}: expected one set {SET_LAYOUT}, got a folder of "
                             f"sessions {str(test)!r}; give one session")
        find_sessions(data, names[0])        # a folder in one layout or the other
        return CROSS_SESSION
    if Path(data).is_dir() and find_sessions(data, names[0]):
        return LEAVE_ONE_SESSION_OUT
    return LEAVE_ONE_OUT


def plan_replays(data: str | Path, n: int, seed: int, *, test: str | Path | None = None,
                 observe: Sequence[str] | None = None,
                 options: Mapping[str, Any] | None = None, spec=None) -> list[Replay]:
    """The ``n`` episodes replaying recorded trials, in the mode :func:`replay_mode` says.

    Parameters
    ----------
    data : str or Path
        One set ``<root>/<task>/<trial>.csv``, or a folder of sessions.
    n : int
        Episodes (>= 1).
    seed : int
        Episode ``i`` resets with ``seed + i``; the trials are drawn with it.
    test : str or Path, optional
        One set replayed with a model of all of ``data`` (cross-session).
    observe : sequence of str, optional
        The modalities the models are fitted on (default the hand).
    options : mapping, optional
        Extra ``reset`` options for every episode.
    spec : DataSpec, optional
        The sets' layout (:mod:`sandbox.data.spec`); the replayed motion (its ``hand``
        and the body modalities it has) is then loaded with it and given to the
        environment as its ``motion``. Its robot part is Baxter's 7 joints or a
        task-space position (m), which the arms follow through their inverse
        kinematics (:mod:`sandbox.episodes.steering`).

    Returns
    -------
    list of Replay

    Raises
    ------
    ValueError
        A set without a usable trial; tasks to replay that the trials fitted on
        have none of (named); a ``test`` that is not one set.
    """
    mode = replay_mode(data, test)
    observe = tuple(observe or (spec.observe if spec is not None else ("hand",)))
    options = dict(options or {})
    if mode == LEAVE_ONE_OUT:
        return _leave_one_out(_load(Path(data), str(data), observe, spec=spec), n, seed,
                              options)
    fit = _load_sets(Path(data), observe, spec)
    if test is not None:                    # cross-session
        replayed = _load(Path(test), str(test), observe, "test", spec)
        return _cross_session(fit, str(data), replayed, n, seed, options)
    return _leave_one_session_out(fit, n, seed, options)


def _load(folder: Path, name: str, observe, option: str = "data", spec=None) -> _Set:
    """The usable trials of one set; ``ValueError`` (one line) if it has none."""
    import warnings

    from sandbox.data.recorded import SkippedTrialWarning, load_recorded

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", SkippedTrialWarning)   # counted in the error
            demos, skipped = load_recorded(folder, observe=observe, spec=spec)
    except ValueError as error:
        raise ValueError(f"{option}: {str(error).removeprefix('data: ')}") from None
    if not demos:
        from sandbox.data.skipped import no_usable

        raise no_usable(f"{option} {folder}", [f"skipped {f}: {r}" for f, r in skipped])
    return _Set(name, folder, demos, spec)


def _load_sets(root: Path, observe, spec=None) -> list[_Set]:
    """The sessions of a folder of sessions (sorted by name), or ``root`` as one set."""
    from sandbox.data.sessions import find_sessions

    sessions = find_sessions(root, "data")
    if not sessions:
        return [_load(root, str(root), observe, spec=spec)]
    return [_load(folder, folder.name, observe, f"data session {folder.name}", spec)
            for folder in sessions]


def _picks(size: int, n: int, seed: int) -> list[int]:
    """``n`` indices into a pool of ``size`` drawn from ``seed`` (each once while they last)."""
    rng = np.random.default_rng(seed)
    return [int(k) for k in rng.choice(size, size=n, replace=n > size)]


def _fit(demos: list):
    """An :class:`~sandbox.core.IProMP` of every task of ``demos``, with their geometry."""
    from sandbox.core import IProMP
    from sandbox.data.geometry import attach_geometry
    from sandbox.episodes.libraries import remember_demos

    return remember_demos(attach_geometry(IProMP().fit(demos), demos), demos)


def _replay(seed: int, model, held_out, replayed: _Set, options: dict,
            provenance: dict) -> Replay:
    """The episode replaying ``held_out`` (a trial of ``replayed``) with ``model``."""
    if replayed.spec is None:
        opts = {**grasp_options(model), **options, "source": str(replayed.folder),
                "task": held_out.task, "trial": Path(held_out.source).name}
    else:                           # the environment cannot read the layout: give it the motion
        opts = {**grasp_options(model), **options, "motion": _motion(held_out, replayed.spec)}
    return Replay(seed, model, opts, held_out, {**provenance, "session": replayed.name})


def _motion(held_out, spec):
    """The environment's motion of a trial loaded with ``spec`` (:func:`spec_motion`)."""
    return spec_motion(held_out.source, held_out.task, spec,
                       [m.name for m in held_out.modalities], smooth=held_out)


def spec_motion(path, task: str, spec, observe, smooth=None):
    """The environment's replay (``HumanMotion``) of the trial ``path`` of a set described
    by ``spec``: its smoothed ``hand`` as the true motion, its causal stream as measured
    (:func:`sandbox.envs.sources.motion_of`); ``smooth``: the smoothed trial if loaded.

    ``ValueError`` if ``observe`` has no ``hand`` (the environment's human is driven by it).
    """
    from sandbox.data.recorded import load_trial
    from sandbox.envs.sources import motion_of

    if "hand" not in list(observe):
        raise ValueError("spec: expected the observed modalities to include 'hand' (x, y, z, "
                         "m): the environment's human is driven by it")
    if smooth is None:
        smooth = load_trial(path, task=task, spec=spec, observe=list(observe))
    causal = load_trial(path, task=task, spec=spec, observe=list(observe), preprocess="causal")
    return motion_of(smooth, causal)


def _leave_one_out(data: _Set, n: int, seed: int, options: dict) -> list[Replay]:
    """Each episode replays a random trial with a model fitted on all the other trials."""
    out = []
    for i, k in enumerate(_picks(len(data.demos), n, seed)):
        # Any: a Demonstration is frozen, the core's DemonstrationLike declares plain attributes
        others: list[Any] = [d for j, d in enumerate(data.demos) if j != k]
        provenance = {"mode": LEAVE_ONE_OUT, "train": f"{data.name} (the other trials)",
                      "n_train": len(others)}
        out.append(_replay(seed + i, _fit(others), data.demos[k], data, options, provenance))
    return out


def _cross_session(fit: list[_Set], train: str, replayed: _Set, n: int, seed: int,
                   options: dict) -> list[Replay]:
    """Every episode replays a trial of ``replayed`` with one model of all of ``fit``."""
    demos: list[Any] = [d for s in fit for d in s.demos]
    check_tasks(demos, replayed.demos, f"test: {replayed.name}", train)
    model = _fit(demos)
    provenance = {"mode": CROSS_SESSION, "train": train, "n_train": len(demos)}
    return [_replay(seed + i, model, replayed.demos[k], replayed, options, provenance)
            for i, k in enumerate(_picks(len(replayed.demos), n, seed))]


def _leave_one_session_out(sessions: list[_Set], n: int, seed: int,
                           options: dict) -> list[Replay]:
    """Each episode replays a trial drawn from all sessions with a model of the others."""
    from sandbox.data.sessions import SESSIONS_LAYOUT

    if len(sessions) < 2:
        raise ValueError(f"data: expected at least 2 sessions {SESSIONS_LAYOUT} to leave one "
                         f"out, got {len(sessions)}")
    others = [[d for s in sessions if s is not left for d in s.demos] for left in sessions]
    for left, rest in zip(sessions, others):
        check_tasks(rest, left.demos, f"data: session {left.name}", "the other sessions")
    pool = [(i, d) for i, s in enumerate(sessions) for d in s.demos]
    models: dict[int, Any] = {}             # fitted once per left-out session
    out = []
    for i, k in enumerate(_picks(len(pool), n, seed)):
        s, held_out = pool[k]
        if s not in models:
            models[s] = _fit(others[s])
        provenance = {"mode": LEAVE_ONE_SESSION_OUT,
                      "train": ", ".join(x.name for x in sessions if x is not sessions[s]),
                      "n_train": len(others[s])}
        out.append(_replay(seed + i, models[s], held_out, sessions[s], options, provenance))
    return out


def check_tasks(fit: Sequence, replayed: Sequence, what: str, fitted: str) -> None:
    """``ValueError`` unless every task of the demos ``replayed`` has demos in ``fit``.

    ``what`` names the replayed trials in the message (e.g. ``"test: late"``),
    ``fitted`` the trials fitted on.
    """
    known = list(dict.fromkeys(d.task for d in fit))
    missing = [t for t in dict.fromkeys(d.task for d in replayed) if t not in known]
    if missing:
        raise ValueError(f"{what} has tasks {missing} that {fitted} has no trials of "
                         f"(it has {known})")
