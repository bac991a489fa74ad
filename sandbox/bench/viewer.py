"""Viewer benchmark: build time, per-frame cost, replay size (``python -m sandbox.bench.viewer``).

Two recordings of 3 s at 30 fps, no server (offline scene):

1. ``baxter``: Baxter alone, the left arm sweeping between two postures;
2. ``episode``: the handover environment (Baxter, hand, table, objects) driven
   by the dynamic IProMP policy, with the prediction overlays (seed 0, human
   speed 0.7: a 3.7 s episode, of which the first 3 s are recorded).

Printed per mesh resolution: mirror build time (cold: meshes read and
simplified; warm: from the cache), median and max per-frame update time
(mirror only, and overlays), the number of triangles sent and the size of the
saved HTML replay. Timings depend on the machine; set OPENBLAS_NUM_THREADS=1.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np

FPS, DURATION = 30.0, 3.0


def _ms(values: list[float]) -> str:
    return f"median {1e3 * np.median(values):.2f} ms, max {1e3 * np.max(values):.2f} ms"


def _save(viewer, name: str, folder: Path) -> str:
    start = time.perf_counter()
    path = viewer.save_html(folder / f"{name}.html")
    return f"{path.stat().st_size / 1e6:.2f} MB (written in {time.perf_counter() - start:.2f} s)"


def bench_baxter(resolution: float | None, folder: Path, live: bool = False) -> None:
    """Baxter alone, the left arm sweeping for 3 s (through a live server if ``live``)."""
    from sandbox.robot import q_home
    from sandbox.robot.bullet import connect, load_baxter, reset_arm
    from sandbox.viz import Viewer
    from sandbox.viz.meshes import _load_cached

    client = connect()
    baxter = load_baxter(client)
    reset_arm(baxter, q_home())
    builds = []
    for cache in ("cold", "warm"):
        if cache == "cold":
            _load_cached.cache_clear()
        viewer = Viewer(fps=FPS, resolution=resolution, live=live and cache == "warm")
        start = time.perf_counter()
        mirror = viewer.add_baxter(baxter)
        builds.append(f"{cache} {time.perf_counter() - start:.2f} s")
    swing = np.array([0.6, -0.4, 0.0, -0.6, 0.0, 0.5, 0.0])
    frames = []
    for t in np.arange(0.0, DURATION + 1e-9, 1.0 / FPS):
        reset_arm(baxter, q_home() + swing * np.sin(np.pi * t / DURATION))
        start = time.perf_counter()
        viewer.update(t)
        frames.append(time.perf_counter() - start)
    viewer.close()
    label = "baxter (live)" if live else "baxter"
    print(f"  {label}: build {', '.join(builds)}; {mirror.n_triangles} triangles; "
          f"{len(frames)} frames, update {_ms(frames)}; replay {_save(viewer, 'baxter', folder)}")
    client.disconnect()


def bench_episode(resolution: float | None, folder: Path) -> None:
    """The environment with the IProMP policy and the overlays."""
    import gymnasium as gym

    import sandbox.envs  # noqa: F401  (registers the environments)
    from sandbox.episodes.policies import IProMPPolicy, fit_family_model
    from sandbox.viz import Viewer

    env = gym.make("sandbox/BaxterHandoverDiverging-v1")
    model = fit_family_model("diverging")
    policy = IProMPPolicy(model, dow_t=0.2)
    obs, _ = env.reset(seed=0, options={"speed": 0.7})
    viewer = Viewer(fps=FPS, resolution=resolution)
    start = time.perf_counter()
    viewer.add_simulation(env.unwrapped.sim)
    build = time.perf_counter() - start
    overlay = viewer.add_overlay(model.tasks, rng=np.random.default_rng(0))
    mirror_s, overlay_s, t, done = [], [], 0.0, False
    while not done and t < DURATION:
        obs, _, terminated, truncated, _ = env.step(policy(obs))
        done, t = terminated or truncated, float(obs["time"][0])
        start = time.perf_counter()
        if viewer.begin(t):
            for body in viewer.bodies.values():
                body.update()
            mirror_s.append(time.perf_counter() - start)
            start = time.perf_counter()
            overlay.show(policy.beliefs, t, executed_q=obs["q"])
            overlay_s.append(time.perf_counter() - start)
    print(f"  episode : build {build:.2f} s (warm) for {len(viewer.bodies)} bodies; "
          f"{t:.2f} s, {len(mirror_s)} frames: mirror {_ms(mirror_s)}, overlays "
          f"{_ms(overlay_s)}; {policy.beliefs.n_updates} updates; "
          f"replay {_save(viewer, 'episode', folder)}")
    env.close()


def main(argv: list[str] | None = None) -> int:
    """Run ``python -m sandbox.bench.viewer`` with ``argv``; return the exit status."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=None, help="folder for the replays (default: temp)")
    parser.add_argument("--live", action="store_true",
                        help="also time Baxter through a live meshcat server (no browser)")
    parser.add_argument("--resolutions", default="0.002,none",
                        help="mesh grids in m, comma separated ('none': full meshes)")
    args = parser.parse_args(argv)
    folder = Path(args.out or tempfile.mkdtemp(prefix="viz-bench-"))
    folder.mkdir(parents=True, exist_ok=True)
    print(f"replays in {folder} (OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')})")
    for text in args.resolutions.split(","):
        resolution = None if text.strip().lower() == "none" else float(text)
        print(f"resolution {resolution}:")
        sub = folder / f"res-{text.strip()}"
        sub.mkdir(exist_ok=True)
        bench_baxter(resolution, sub)
        if args.live:
            bench_baxter(resolution, sub, live=True)
        bench_episode(resolution, sub)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
