"""Soak: many steps and resets of an environment with the dynamic policy, watching resources.

``python -m sandbox.bench.soak [--steps 10000] [--reset-every 45]`` steps
``sandbox/BaxterHandoverDiverging-v1`` with :class:`~sandbox.episodes.policies.IProMPPolicy`
choosing the actions, resets at the end of every episode and at least every
``reset_every`` steps (so 10,000 steps make 200+ resets), and prints JSON: the
resident memory (MiB) and the open file descriptors at the start and after
each tenth of the run, and their growth from the first tenth to the end
(the first tenth holds the one-off warm-up: caches, the fitted model).

Linux only (reads ``/proc/self``).
"""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path


def _rss_mib() -> float:
    """Resident set size of this process (MiB)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024.0
    raise RuntimeError("VmRSS not found in /proc/self/status")


def _open_fds() -> int:
    return len(os.listdir("/proc/self/fd"))


def soak(steps: int = 10_000, reset_every: int = 45, seed: int = 0) -> dict:
    """Run the soak (see the module docstring); return the samples and the growth."""
    import gymnasium as gym
    import numpy as np

    import sandbox.envs  # noqa: F401  (registers the environments)
    from sandbox.episodes.policies import IProMPPolicy, fit_family_model

    if steps < 10 or reset_every < 1:
        raise ValueError(f"steps, reset_every: expected >= 10 and >= 1, got {steps}, "
                         f"{reset_every}")
    env = gym.make("sandbox/BaxterHandoverDiverging-v1")
    policy = IProMPPolicy(fit_family_model("diverging"))
    samples = [{"step": 0, "rss_mib": _rss_mib(), "fds": _open_fds()}]
    resets, since = 0, 0
    try:
        obs, _ = env.reset(seed=seed)
        policy.reset()
        for step in range(1, steps + 1):
            obs, _, terminated, truncated, _ = env.step(policy(obs))
            since += 1
            if terminated or truncated or since >= reset_every:
                obs, _ = env.reset(seed=seed + step)
                policy.reset()
                resets, since = resets + 1, 0
            if step % max(1, steps // 10) == 0:
                samples.append({"step": step, "rss_mib": _rss_mib(), "fds": _open_fds()})
    finally:
        env.close()
    first, last = samples[1] if len(samples) > 1 else samples[0], samples[-1]
    return {"steps": steps, "resets": resets, "samples": samples,
            "rss_growth_mib": round(last["rss_mib"] - first["rss_mib"], 2),
            "fd_growth": last["fds"] - first["fds"],
            "rss_growth_per_1000_steps_mib": round(
                1000 * (last["rss_mib"] - first["rss_mib"])
                / max(1, last["step"] - first["step"]), 3),
            "finite_actions": bool(np.isfinite(policy._target).all())
            if policy._target is not None else True}


def main(argv=None) -> int:
    """Run ``python -m sandbox.bench.soak`` with ``argv``; return the exit status."""
    parser = argparse.ArgumentParser(prog="python -m sandbox.bench.soak", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--steps", type=int, default=10_000)
    parser.add_argument("--reset-every", type=int, default=45)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    print(json.dumps(soak(args.steps, args.reset_every, args.seed), indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
