"""Gymnasium handover environments, installed as :mod:`sandbox.envs`.

Importing this package registers the environments in the ``sandbox``
namespace; :data:`ENV_IDS` lists them::

    import gymnasium as gym
    import sandbox.envs

    env = gym.make("sandbox/BaxterHandoverDiverging-v1")
    obs, info = env.reset(seed=0, options={"task": "left"})

``gym.register_envs(sandbox.envs)`` says so to linters (the import did the
registering). Without the import,
``gym.make("sandbox.envs:sandbox/BaxterHandover-v1")`` imports it first.
``gym.make_vec(id, num_envs=N)`` gives N environments in worker processes
started from a forkserver (:mod:`sandbox.envs.vector`);
``vectorization_mode="sync"`` or ``"async"`` gives Gymnasium's own.

Any arm (issue 23): ``gym.make("sandbox/Handover-v2", robot="panda")`` (or
``"sandbox/HandoverDiverging-v2"``; :data:`ROBOT_IDS`) with ``robot`` one of
``baxter`` (default), ``panda``, ``ur5``, ``kinova``; the Baxter ids below take
``robot=`` too and stay registered as aliases for one release.

``sandbox/BaxterHandover-v1`` hands over objects (synthetic box, glasses case
and tape, or a recorded trial with ``options={"source": DIR}``);
``sandbox/BaxterHandoverDiverging-v1`` plays the diverging tasks (left, right,
up, down, straight). See :class:`BaxterHandoverEnv`. The ``-v0`` ids
(:data:`LEGACY_IDS`) stay registered for one release with v0's observation
(no ``arm``, ``emg``).

Modules: ``pybullet`` (the only one importing PyBullet: :class:`Simulation`),
``robot`` (Baxter's arm and gripper), ``human`` (hand motion and body),
``sources`` (synthetic, recorded and scripted waypoint motions), ``teleop`` (a
hand driven by velocity commands), ``task`` (objects, handover, reward),
``options`` (``reset`` options), ``vector`` (vector environments), ``handover``
(the environment; render modes ``"human"``, a live meshcat viewer, and ``"rgb_array"``).
"""

from __future__ import annotations

import gymnasium as gym

from sandbox.envs.handover import BaxterHandoverEnv
from sandbox.envs.task import RewardWeights

#: What ``gym.make_vec`` calls (:func:`sandbox.envs.vector.make_vector_env`; named, not
#: imported, so the vector module may read :data:`_VARIANTS` without an import cycle).
VECTOR_ENTRY_POINT = "sandbox.envs.vector:make_vector_env"
#: Steps before truncation (6 s at the default 50 Hz).
MAX_EPISODE_STEPS = 300

#: (id, synthetic family, observe the arm and EMG) of every registered environment.
_VARIANTS = (
    ("sandbox/BaxterHandover-v1", "objects", True),
    ("sandbox/BaxterHandoverDiverging-v1", "diverging", True),
    ("sandbox/BaxterHandover-v0", "objects", False),
    ("sandbox/BaxterHandoverDiverging-v0", "diverging", False),
)

#: The current ids (objects, diverging); :data:`LEGACY_IDS` keep v0's observation.
ENV_IDS: list[str] = []
#: The v0 ids (no ``arm``/``emg`` in the observation), kept for one release.
LEGACY_IDS: list[str] = []
for _env_id, _family, _body in _VARIANTS:
    if _env_id not in gym.registry:
        gym.register(
            id=_env_id,
            entry_point="sandbox.envs.handover:BaxterHandoverEnv",
            vector_entry_point=VECTOR_ENTRY_POINT,
            kwargs={"family": _family, "observe_body": _body},
            max_episode_steps=MAX_EPISODE_STEPS,
        )
    (ENV_IDS if _body else LEGACY_IDS).append(_env_id)

#: Ids that do not name Baxter: (id, synthetic family); ``robot=`` chooses the arm
#: (:data:`sandbox.robot.arms.ROBOTS`, default ``"baxter"``). The ``sandbox/BaxterHandover*``
#: ids are the same environment (they take ``robot=`` too), kept as aliases for one release.
ROBOT_IDS: list[str] = []
for _env_id, _family in (("sandbox/Handover-v2", "objects"),
                         ("sandbox/HandoverDiverging-v2", "diverging")):
    if _env_id not in gym.registry:
        gym.register(
            id=_env_id,
            entry_point="sandbox.envs.handover:BaxterHandoverEnv",
            vector_entry_point=VECTOR_ENTRY_POINT,
            kwargs={"family": _family, "observe_body": True, "robot": "baxter"},
            max_episode_steps=MAX_EPISODE_STEPS,
        )
    ROBOT_IDS.append(_env_id)

__all__ = ["ENV_IDS", "LEGACY_IDS", "MAX_EPISODE_STEPS", "ROBOT_IDS", "BaxterHandoverEnv",
           "RewardWeights"]
