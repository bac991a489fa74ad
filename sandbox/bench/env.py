"""Speed of the handover environments (merged into ``python -m sandbox bench --json``).

* ``env_steps_per_s``: ``env.step`` with random actions through ``gym.make``'s
  wrappers (``sandbox/BaxterHandoverDiverging-v1``), resetting when an episode ends.
* ``raw_pybullet_steps_per_s``: the same scene (the environment's own client,
  bodies and constraints) stepped directly: per step, the arm's and fingers'
  motor targets are set and the physics advanced by the same number of
  substeps, nothing else (no observation, no hand motion, no reward).
* ``env_raw_ratio``: their ratio (issue 25's target >= 0.9). Both advance the same physics
  substeps per step. ``env_raw_cpu_ratio``: the same ratio in this process's CPU time (the
  raw block's CPU seconds over the env block's, medians), which other processes on the
  machine sway less than the wall time. The environment is reset before each of its
  blocks; a block that reaches the episode's end (``n_steps`` >= 300, the time limit)
  holds one more reset (a new synthetic reach is generated), which the raw block never
  has. ``env_reset_ms``: one reset's median time (ms), so that it can be taken out of such
  a block's time.
* ``env_v0_steps_per_s``: the same random stepping of the legacy hand-only id
  (``sandbox/BaxterHandoverDiverging-v0``), and ``env_v1_v0_ratio`` the cost of
  observing the arm and EMG (target >= 0.9).
* ``policy_steps_per_s``: steps per second with the dynamic policy
  (:class:`sandbox.episodes.policies.IProMPPolicy`, ``dow_t = 0.1`` s) choosing the actions.
* ``env_steps_per_s_by_robot``: random stepping of ``sandbox/HandoverDiverging-v2`` with
  each arm (``robot=``: baxter, panda, ur5, kinova), blocks alternating between the arms,
  medians; ``policy_steps_per_s_by_robot``: the dynamic policy in the loop for each arm
  (another arm than Baxter retargets every command through its IK).

:func:`run_vector_benchmarks` (the bench command runs it too):

* ``vector_steps_per_s``: sub-env steps per second of ``gym.make_vec(ENV_ID, N)``
  (async workers from a forkserver) for N = 1, 2, 4, and ``vector_speedup`` =
  N=4 / N=1 (target >= 1.6 on 2 idle cores); ``gymnasium_benchmark_step_per_s``:
  :func:`gymnasium.utils.performance.benchmark_step` on one env, for comparison;
  ``cpu_count`` and the 1-minute load average before and after, since other
  processes on the machine take cores from the workers.

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
#: The id that takes any arm (``robot=``), timed per arm.
ROBOT_ENV_ID = "sandbox/HandoverDiverging-v2"


def _make_env(env_id: str = ENV_ID, **kwargs):
    import gymnasium as gym

    import sandbox.envs  # noqa: F401  (registers the environments)

    return gym.make(env_id, **kwargs)


def _env_block(env, n_steps: int, rng: np.random.Generator) -> float:
    """Seconds for ``n_steps`` random-action steps (resets included when episodes end)."""
    return _env_block_times(env, n_steps, rng)[0]


def _env_block_times(env, n_steps: int, rng: np.random.Generator) -> tuple[float, float]:
    """:func:`_env_block`'s wall and CPU seconds."""
    low, high = env.action_space.low, env.action_space.high   # looked up once, as the raw block
    start, cpu = time.perf_counter(), time.process_time()
    for _ in range(n_steps):
        action = rng.uniform(low, high)
        _, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            env.reset()
    return time.perf_counter() - start, time.process_time() - cpu


def _raw_block(env, n_steps: int, rng: np.random.Generator) -> tuple[float, float]:
    """Wall and CPU seconds for ``n_steps`` steps of the same scene driven directly through
    PyBullet."""
    from sandbox.robot.pybullet_quiet import pybullet

    base = env.unwrapped
    client, body = base.sim.client, base.robot.baxter.body
    arm, fingers = list(base.robot.baxter.arm), list(base.robot.baxter.fingers)
    forces = base.robot.max_force.tolist()
    low, high = base.action_space.low[:7], base.action_space.high[:7]
    start, cpu = time.perf_counter(), time.process_time()
    for _ in range(n_steps):
        target = rng.uniform(low, high)
        client.setJointMotorControlArray(body, arm, pybullet.POSITION_CONTROL,
                                         targetPositions=target.tolist(), forces=forces)
        client.setJointMotorControlArray(body, fingers, pybullet.POSITION_CONTROL,
                                         targetPositions=[0.0, 0.0], forces=[20.0, 20.0])
        for _ in range(base.substeps):
            client.stepSimulation()
    return time.perf_counter() - start, time.process_time() - cpu


def env_vs_raw(n_steps: int = 200, blocks: int = 5, seed: int = 0) -> dict[str, float]:
    """Median -v1, -v0 and raw PyBullet steps per second over alternating blocks, and ratios."""
    env, legacy = _make_env(), _make_env(LEGACY_ENV_ID)
    rng = np.random.default_rng(seed)
    try:
        for e in (env, legacy):
            e.reset(seed=seed)
            _env_block(e, 20, rng)  # warm up
        env_times, legacy_times, raw_times, resets = [], [], [], []
        for _ in range(blocks):
            env_times.append(_env_block_times(env, n_steps, rng))
            legacy_times.append(_env_block(legacy, n_steps, rng))
            env.reset()
            raw_times.append(_raw_block(env, n_steps, rng))
            start = time.perf_counter()
            env.reset()
            resets.append(time.perf_counter() - start)
    finally:
        env.close()
        legacy.close()
    (env_wall, env_cpu), (raw_wall, raw_cpu) = (np.median(env_times, axis=0),
                                                np.median(raw_times, axis=0))
    env_rate, raw_rate = n_steps / float(env_wall), n_steps / float(raw_wall)
    legacy_rate = n_steps / float(np.median(legacy_times))
    return {"env_steps_per_s": env_rate, "raw_pybullet_steps_per_s": raw_rate,
            "env_raw_ratio": env_rate / raw_rate,
            "env_raw_cpu_ratio": float(raw_cpu) / float(env_cpu),
            "env_v0_steps_per_s": legacy_rate, "env_v1_v0_ratio": env_rate / legacy_rate,
            "env_reset_ms": 1e3 * float(np.median(resets))}


def policy_steps_per_s(n_episodes: int = 3, dow_t: float = 0.1, seed: int = 0,
                       robot: str = "baxter") -> float:
    """Environment steps per second with the dynamic policy in the loop (whole episodes)."""
    from sandbox.episodes.policies import IProMPPolicy, fit_family_model

    env = _make_env() if robot == "baxter" else _make_env(ROBOT_ENV_ID, robot=robot)
    policy = IProMPPolicy(fit_family_model("diverging"), dow_t=dow_t, robot=robot)
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


def by_robot(n_steps: int = 200, blocks: int = 3, seed: int = 0) -> dict[str, float]:
    """Median random-action steps per second of ``sandbox/HandoverDiverging-v2`` per arm."""
    from sandbox.robot.arms import ROBOTS

    envs = {robot: _make_env(ROBOT_ENV_ID, robot=robot) for robot in ROBOTS}
    rng = np.random.default_rng(seed)
    times: dict[str, list[float]] = {robot: [] for robot in ROBOTS}
    try:
        for env in envs.values():
            env.reset(seed=seed)
            _env_block(env, 20, rng)  # warm up
        for _ in range(blocks):
            for robot, env in envs.items():
                times[robot].append(_env_block(env, n_steps, rng))
    finally:
        for env in envs.values():
            env.close()
    return {robot: n_steps / float(np.median(t)) for robot, t in times.items()}


def run_env_benchmarks() -> dict:
    """All environment figures (see the module docstring), rounded for printing."""
    from sandbox.robot.arms import ROBOTS

    result = env_vs_raw()
    result["policy_steps_per_s"] = policy_steps_per_s()
    out: dict = {key: round(value, 3 if key.endswith("ratio") else 1)
                 for key, value in result.items()}
    out["env_steps_per_s_by_robot"] = {r: round(v, 1) for r, v in by_robot().items()}
    out["policy_steps_per_s_by_robot"] = {
        r: round(policy_steps_per_s(n_episodes=2, robot=r), 1) for r in ROBOTS}
    return out


# ---------------------------------------------------------------- vector environments
#: Sub-environment counts of the vector benchmark (async, forkserver workers).
VECTOR_SIZES = (1, 2, 4)


def vector_steps_per_s(sizes: tuple[int, ...] = VECTOR_SIZES, block_s: float = 2.0,
                       blocks: int = 3, seed: int = 0) -> dict[str, float]:
    """Sub-env steps per second of ``gym.make_vec(ENV_ID, N)`` for each N (async workers).

    All vector envs are made first, then timed in alternating blocks of
    ``block_s`` seconds with :func:`gymnasium.utils.performance.benchmark_vector_step`
    (random actions; the steps that only autoreset are not counted); each
    figure is the median over ``blocks``. Returns ``{N: steps/s}``.
    """
    import gymnasium as gym

    import sandbox.envs  # noqa: F401  (registers the environments)

    benchmark_vector_step = _vector_benchmark()
    envs = {n: gym.make_vec(ENV_ID, num_envs=n) for n in sizes}
    rates: dict[int, list[float]] = {n: [] for n in sizes}
    try:
        for _ in range(blocks):
            for n, env in envs.items():
                rates[n].append(benchmark_vector_step(env, target_duration=block_s, seed=seed))
    finally:
        for env in envs.values():
            env.close()
    return {n: float(np.median(r)) for n, r in rates.items()}


def gymnasium_step_per_s(target_duration: float = 5.0, seed: int = 0) -> float:
    """Steps/s of one ``gym.make(ENV_ID)``: :func:`gymnasium.utils.performance.benchmark_step`."""
    from gymnasium.utils.performance import benchmark_step

    env = _make_env()
    try:
        return float(benchmark_step(env, target_duration=target_duration, seed=seed))
    finally:
        env.close()


def run_vector_benchmarks() -> dict:
    """``vector_steps_per_s`` ({"1": ..., "2": ..., "4": ...}), the speed-up of the largest N
    over N = 1 (``vector_speedup``), the host's CPU count and load average while it ran, and
    Gymnasium's ``benchmark_step`` figure for one env (``gymnasium_benchmark_step_per_s``)."""
    import os

    load_before = os.getloadavg()[0]
    rates = vector_steps_per_s()
    single = gymnasium_step_per_s()
    largest = max(rates)
    return {"vector_steps_per_s": {str(n): round(r, 1) for n, r in rates.items()},
            "vector_speedup": round(rates[largest] / rates[min(rates)], 3),
            "gymnasium_benchmark_step_per_s": round(single, 1),
            "cpu_count": os.cpu_count(),
            "load_average_1min": [round(load_before, 2), round(os.getloadavg()[0], 2)]}


def _vector_benchmark():
    """gymnasium's ``benchmark_vector_step`` (gymnasium >= 1.4), else :func:`_vector_steps`."""
    try:
        from gymnasium.utils.performance import benchmark_vector_step
    except ImportError:   # gymnasium 1.1 - 1.3
        return _vector_steps
    return benchmark_vector_step


def _vector_steps(env, target_duration: float = 5.0, seed: int | None = None) -> float:
    """Sub-env steps per second of ``env`` (a vector env): gymnasium 1.4's count, where a
    step that only autoresets a sub-env (next-step mode) is not counted."""
    from gymnasium.vector import AutoresetMode

    env.action_space.seed(seed)
    env.reset(seed=seed)
    env.step(env.action_space.sample())        # warm up outside the timing
    env.reset(seed=seed)
    next_step = env.metadata.get("autoreset_mode", AutoresetMode.NEXT_STEP) \
        == AutoresetMode.NEXT_STEP
    steps, done = 0, np.zeros(env.num_envs, dtype=bool)
    start = time.perf_counter()
    while True:
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        steps += env.num_envs - (int(np.count_nonzero(done)) if next_step else 0)
        done = np.logical_or(terminated, truncated)
        elapsed = time.perf_counter() - start
        if elapsed > target_duration:
            return steps / elapsed
