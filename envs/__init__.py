"""Gymnasium handover environments, installed as :mod:`sandbox.envs`.

Importing this package registers the environments in the ``sandbox``
namespace; :data:`ENV_IDS` lists them::

    import gymnasium as gym
    import sandbox.envs

    env = gym.make("sandbox/BaxterHandoverDiverging-v0")
    obs, info = env.reset(seed=0, options={"task": "left"})

Without the import, ``gym.make("sandbox.envs:sandbox/BaxterHandover-v0")``
imports it first. ``sandbox/BaxterHandover-v0`` hands over objects (synthetic
box, glasses case and tape, or a recorded trial with ``options={"source":
DIR}``); ``sandbox/BaxterHandoverDiverging-v0`` plays the diverging tasks
(left, right, up, down, straight). See :class:`BaxterHandoverEnv`.

Modules: ``pybullet`` (the only one importing PyBullet: :class:`Simulation`),
``robot`` (Baxter's arm and gripper), ``human`` (hand motion and body),
``sources`` (synthetic, recorded and scripted waypoint motions), ``teleop`` (a
hand driven by velocity commands), ``task`` (objects, handover, reward),
``options`` (``reset`` options), ``handover`` (the environment; render modes
``"human"``, a live meshcat viewer, and ``"rgb_array"``).
"""

from __future__ import annotations

import gymnasium as gym

from sandbox.envs.handover import BaxterHandoverEnv
from sandbox.envs.task import RewardWeights

#: Steps before truncation (6 s at the default 50 Hz).
MAX_EPISODE_STEPS = 300

#: (id, synthetic family) of every registered environment.
_VARIANTS = (
    ("sandbox/BaxterHandover-v0", "objects"),
    ("sandbox/BaxterHandoverDiverging-v0", "diverging"),
)

ENV_IDS: list[str] = []
for _env_id, _family in _VARIANTS:
    if _env_id not in gym.registry:
        gym.register(
            id=_env_id,
            entry_point="sandbox.envs.handover:BaxterHandoverEnv",
            kwargs={"family": _family},
            max_episode_steps=MAX_EPISODE_STEPS,
        )
    ENV_IDS.append(_env_id)

__all__ = ["ENV_IDS", "MAX_EPISODE_STEPS", "BaxterHandoverEnv", "RewardWeights"]
