"""Speed of the handover environments (merged into ``python -m sandbox bench --json``).

* ``env_steps_per_s``: ``env.step`` with random actions through ``gym.make``'s
  wrappers (``sandbox/BaxterHandoverDiverging-v1``), resetting when an episode ends.
* ``raw_pybullet_steps_per_s``: the same scene (the environment's own client,
  bodies and constraints) stepped directly: per step, the arm's and fingers'
  motor targets are set and the physics advanced by the same number of
  substeps, nothing else (no observation, no hand motion, no reward).
* ``env_raw_ratio``: their ratio (target >= 0.5).
* ``env_v0_steps_per_s``: the same random stepping of the legacy hand-only id
  (``sandbox/BaxterHandoverDiverging-v0``), and ``env_v1_v0_ratio`` the cost of
  observing the arm and EMG (target >= 0.9).
* ``policy_steps_per_s``: steps per second with the dynamic policy
  (:class:`sandbox.policies.IProMPPolicy`, ``dow_t = 0.1`` s) choosing the actions.

The -v1, -v0 and raw stepping alternate in blocks and each figure is the median over
blocks, so both are measured in the same run under the same load. Run with
``OPENBLAS_NUM_THREADS=1``.
"""

from __future__ import annotations

import time

import numpy as np

ENV_ID = "sandbox/BaxterHandoverDiverging-v1"
#: The legacy id with the hand-only observation, timed beside ``ENV_ID``.
LEGACY_ENV_ID = "sandbox/BaxterHandoverDiverging-v0"


def _make_env(env_id: str = ENV_ID):
    import gymnasium as gym

    import sandbox.envs  # noqa: F401  (registers the environments)

    return gym.make(env_id)


def _env_block(env, n_steps: int, rng: np.random.Generator) -> float:
    """Seconds for ``n_steps`` random-action steps (resets included when episodes end)."""
    start = time.perf_counter()
    for _ in range(n_steps):
        action = rng.uniform(env.action_space.low, env.action_space.high)
        _, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            env.reset()
    return time.perf_counter() - start


def _raw_block(env, n_steps: int, rng: np.random.Generator) -> float:
    """Seconds for ``n_steps`` steps of the same scene driven directly through PyBullet."""
    import pybullet

    base = env.unwrapped
    client, body = base.sim.client, base.robot.baxter.body
    arm, fingers = list(base.robot.baxter.arm), list(base.robot.baxter.fingers)
    forces = base.robot.max_force.tolist()
    low, high = base.action_space.low[:7], base.action_space.high[:7]
    start = time.perf_counter()
    for _ in range(n_steps):
        target = rng.uniform(low, high)
        client.setJointMotorControlArray(body, arm, pybullet.POSITION_CONTROL,
                                         targetPositions=target.tolist(), forces=forces)
        client.setJointMotorControlArray(body, fingers, pybullet.POSITION_CONTROL,
                                         targetPositions=[0.0, 0.0], forces=[20.0, 20.0])
        for _ in range(base.substeps):
            client.stepSimulation()
    return time.perf_counter() - start


def env_vs_raw(n_steps: int = 200, blocks: int = 5, seed: int = 0) -> dict[str, float]:
    """Median -v1, -v0 and raw PyBullet steps per second over alternating blocks, and ratios."""
    env, legacy = _make_env(), _make_env(LEGACY_ENV_ID)
    rng = np.random.default_rng(seed)
    try:
        for e in (env, legacy):
            e.reset(seed=seed)
            _env_block(e, 20, rng)  # warm up
        env_times, legacy_times, raw_times = [], [], []
        for _ in range(blocks):
            env_times.append(_env_block(env, n_steps, rng))
            legacy_times.append(_env_block(legacy, n_steps, rng))
            env.reset()
            raw_times.append(_raw_block(env, n_steps, rng))
            env.reset()
    finally:
        env.close()
        legacy.close()
    env_rate = n_steps / float(np.median(env_times))
    legacy_rate = n_steps / float(np.median(legacy_times))
    raw_rate = n_steps / float(np.median(raw_times))
    return {"env_steps_per_s": env_rate, "raw_pybullet_steps_per_s": raw_rate,
            "env_raw_ratio": env_rate / raw_rate, "env_v0_steps_per_s": legacy_rate,
            "env_v1_v0_ratio": env_rate / legacy_rate}


def policy_steps_per_s(n_episodes: int = 3, dow_t: float = 0.1, seed: int = 0) -> float:
    """Environment steps per second with the dynamic policy in the loop (whole episodes)."""
    from sandbox.policies import IProMPPolicy, fit_family_model

    env = _make_env()
    policy = IProMPPolicy(fit_family_model("diverging"), dow_t=dow_t)
    steps, seconds = 0, 0.0
    try:
        for i in range(n_episodes):
            obs, _ = env.reset(seed=seed + i)
            policy.reset()
            done = False
            start = time.perf_counter()
            while not done:
                obs, _, terminated, truncated, _ = env.step(policy(obs))
                done, steps = terminated or truncated, steps + 1
            seconds += time.perf_counter() - start
    finally:
        env.close()
    return steps / seconds


def run_env_benchmarks() -> dict[str, float]:
    """All environment figures (see the module docstring), rounded for printing."""
    result = env_vs_raw()
    result["policy_steps_per_s"] = policy_steps_per_s()
    return {key: round(value, 3 if key.endswith("ratio") else 1) for key, value in result.items()}
