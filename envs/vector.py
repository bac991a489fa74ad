"""Vector environments of the registered ids: the ``vector_entry_point`` of every id.

``gym.make_vec(id, num_envs=N)`` (no ``vectorization_mode``, or
``"vector_entry_point"``) calls :func:`make_vector_env`: an
:class:`~gymnasium.vector.AsyncVectorEnv` whose workers start from a
``forkserver`` (:data:`VECTOR_CONTEXT`), not by forking the caller, so a
PyBullet client of the parent is never copied into a worker. Every sub-env is a
``gym.make(id)`` environment of its own, with its own PyBullet DIRECT client.

``gym.make_vec(id, N, vectorization_mode="sync" | "async")`` uses Gymnasium's
own vectorizers, which also work; Gymnasium gives ``"async"`` Python's default
start method (``fork`` on Linux before Python 3.14) unless
``vector_kwargs={"context": "forkserver"}`` (or ``"spawn"``) says otherwise.
"""

from __future__ import annotations

from functools import partial
from typing import Any

import gymnasium as gym
from gymnasium.vector import AsyncVectorEnv, AutoresetMode, SyncVectorEnv, VectorEnv

#: Start method of the async workers made by :func:`make_vector_env`.
VECTOR_CONTEXT = "forkserver"
#: Vectorizers :func:`make_vector_env` builds.
VECTORIZERS = ("async", "sync")


def make_vector_env(env_id: str, num_envs: int = 1, *, vectorizer: str = "async",
                    context: str = VECTOR_CONTEXT,
                    autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
                    shared_memory: bool = True, **kwargs: Any) -> VectorEnv:
    """``num_envs`` copies of ``gym.make(env_id, **kwargs)`` stepped together.

    Parameters
    ----------
    env_id : str
        A registered id, e.g. ``"sandbox/BaxterHandoverDiverging-v1"`` (bound at
        registration; ``gym.make_vec`` passes the rest).
    num_envs : int
        Number of sub-environments, >= 1.
    vectorizer : {"async", "sync"}
        One worker process per sub-env, or all in this process.
    context : str
        Start method of the async workers (``"forkserver"`` or ``"spawn"``).
    autoreset_mode : AutoresetMode or str
        Gymnasium's autoreset mode (default next step), declared in the vector
        env's ``metadata["autoreset_mode"]``.
    shared_memory : bool
        Async: observations through shared memory.
    **kwargs
        Arguments of the environment (``render_mode``, ``control_hz``...), and
        ``max_episode_steps``.

    Returns
    -------
    gymnasium.vector.VectorEnv
    """
    if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
        raise ValueError(f"num_envs: expected an integer >= 1, got {num_envs!r}")
    if vectorizer not in VECTORIZERS:
        raise ValueError(f"vectorizer: expected one of {list(VECTORIZERS)}, got {vectorizer!r}")
    if context not in ("forkserver", "spawn"):
        raise ValueError(f"context: expected 'forkserver' or 'spawn' (a fork would copy the "
                         f"parent's PyBullet state), got {context!r}")
    make_one = partial(gym.make, f"sandbox.envs:{env_id}", **kwargs)
    if vectorizer == "sync":
        return SyncVectorEnv([make_one] * num_envs, autoreset_mode=autoreset_mode)
    return AsyncVectorEnv([make_one] * num_envs, context=context, shared_memory=shared_memory,
                          autoreset_mode=autoreset_mode)


def vector_entry_point(env_id: str) -> partial:
    """The ``vector_entry_point`` of ``env_id``: :func:`make_vector_env` bound to it."""
    return partial(make_vector_env, env_id)
