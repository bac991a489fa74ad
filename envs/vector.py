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

from sandbox.envs import _VARIANTS

#: Start method of the async workers made by :func:`make_vector_env`.
VECTOR_CONTEXT = "forkserver"
#: Vectorizers :func:`make_vector_env` builds.
VECTORIZERS = ("async", "sync")


def make_vector_env(num_envs: int = 1, *, family: str = "objects", observe_body: bool = True,
                    vectorizer: str = "async", context: str = VECTOR_CONTEXT,
                    autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
                    shared_memory: bool = True, **kwargs: Any) -> VectorEnv:
    """``num_envs`` copies of a registered environment stepped together.

    ``gym.make_vec`` calls it with the id's registered arguments (``family``,
    ``observe_body``, ``max_episode_steps``) and the caller's.

    Parameters
    ----------
    num_envs : int
        Number of sub-environments, >= 1.
    family, observe_body
        The registered arguments that tell which id each sub-env is made from
        (``gym.make(id, **kwargs)``).
    vectorizer : {"async", "sync"}
        One worker process per sub-env, or all in this process.
    context : {"forkserver", "spawn"}
        Start method of the async workers.
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
    make_one = partial(gym.make, f"sandbox.envs:{env_id_of(family, observe_body)}", **kwargs)
    if vectorizer == "sync":
        return SyncVectorEnv([make_one] * num_envs, autoreset_mode=autoreset_mode)
    return AsyncVectorEnv([make_one] * num_envs, context=context, shared_memory=shared_memory,
                          autoreset_mode=autoreset_mode)


def env_id_of(family: str, observe_body: bool) -> str:
    """The registered id made with these arguments (``ValueError`` if there is none)."""
    for env_id, variant_family, body in _VARIANTS:
        if (variant_family, body) == (family, observe_body):
            return env_id
    raise ValueError(f"family, observe_body: expected one of "
                     f"{[(f, b) for _, f, b in _VARIANTS]}, got {(family, observe_body)!r}")
