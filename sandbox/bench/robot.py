"""Measure the robot model: load time, FK against the recordings, IK accuracy and speed.

Run ``python -m sandbox.bench.robot [--data DIR] [--targets N]``; with
``OPENBLAS_NUM_THREADS=1`` for stable timings. Prints one line per figure.
"""

from __future__ import annotations

import argparse
import csv
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from sandbox.robot.facts import ARM_JOINTS, TIP_LINK
from sandbox.robot.kinematics import BaxterKinematics, q_home


def front_targets(kin: BaxterKinematics, n: int, rng: np.random.Generator, link: str) -> np.ndarray:
    """Reachable targets (n, 3) m: FK of random in-limit configurations in front of Baxter."""
    q = rng.uniform(kin.lower, kin.upper, size=(40 * n, 7))
    p = kin.fk(q, link=link)
    front = (p[:, 0] > 0.4) & (p[:, 1] > -0.2) & (p[:, 2] > -0.4) & (p[:, 2] < 0.7)
    return p[front][:n]


def recorded_fk_offsets(kin: BaxterKinematics, folder: Path) -> tuple[int, np.ndarray]:
    """FK(left_*) - baxter_left_hand_* (m) for every row of every trial in ``folder``."""
    files = sorted(folder.glob("*/*.csv"))
    diffs = []
    for path in files:
        with open(path, newline="") as handle:
            rows = csv.reader(handle)
            header = next(rows)
            data = np.array([[float(v) for v in row] for row in rows])
        q = data[:, [header.index(n) for n in ARM_JOINTS]]
        hand = data[:, [header.index(f"baxter_left_hand_{a}") for a in "xyz"]]
        diffs.append(kin.fk(q, link="left_hand_link") - hand)
    return len(files), np.concatenate(diffs)


def _rate(count: int, seconds: float) -> str:
    return f"{count / seconds:,.0f}/s ({1e3 * seconds / count:.2f} ms each)"


def bench_load() -> None:
    """Time loading Baxter into fresh and reused PyBullet clients."""
    from sandbox.robot.bullet import connect, load_baxter

    client = connect()
    for label in ("first Baxter in a new client", "second Baxter in the same client"):
        start = time.perf_counter()
        load_baxter(client)
        print(f"load: {label}: {time.perf_counter() - start:.2f} s")
    client.disconnect()


def bench_ik(kin: BaxterKinematics, n: int, link: str) -> None:
    """Accuracy and speed of the numpy IK, batched and one target at a time."""
    targets = front_targets(kin, n, np.random.default_rng(0), link)
    kin.ik(targets[:2], link=link)  # warm-up: one-off imports (Q_HOME) out of the timing
    start = time.perf_counter()
    res = kin.ik(targets, link=link)
    batched = time.perf_counter() - start
    inside = np.all((res.q >= kin.lower) & (res.q <= kin.upper))
    print(
        f"ik numpy DLS ({link}, {len(targets)} reachable targets, seed Q_HOME): success "
        f"{res.success.mean():.4f}, error median {1e3 * np.median(res.error):.3f} mm, "
        f"max {1e3 * res.error.max():.3f} mm, within limits {inside}, "
        f"iterations mean {res.iterations.mean():.1f}"
    )
    print(f"ik numpy DLS batched: {_rate(len(targets), batched)}")
    single = targets[:200]
    start = time.perf_counter()
    for target in single:
        kin.ik(target, link=link)
    print(f"ik numpy DLS one target per call: {_rate(len(single), time.perf_counter() - start)}")
    far = np.array([[3.0, 0.0, 0.0], [0.0, 0.0, 3.0], [1.6, 0.5, 0.2]])
    res = kin.ik(far, link=link)
    print(f"ik unreachable targets: success {res.success.tolist()}, error {res.error.round(3)} m")


def bench_bullet_ik(kin: BaxterKinematics, n: int, link: str) -> None:
    """Accuracy and speed of one PyBullet IK call and of the iterated version."""
    from sandbox.robot.bullet import bullet_ik, connect, load_baxter, reset_arm

    client = connect()
    baxter = load_baxter(client)
    targets = front_targets(kin, n, np.random.default_rng(0), link)
    for rounds in (1, 20):
        start = time.perf_counter()
        errors = np.array(
            [
                bullet_ik(baxter, t, q_home(), link=link, tol=0.01, max_rounds=rounds)[1]
                for t in targets
            ]
        )
        elapsed = time.perf_counter() - start
        print(
            f"ik pybullet, {rounds} call(s) max ({len(targets)} targets): within 1 cm "
            f"{np.mean(errors <= 0.01):.4f}, error median {1e3 * np.median(errors):.2f} mm, "
            f"max {1e3 * errors.max():.1f} mm, {_rate(len(targets), elapsed)}"
        )
    errors = []
    movable = sorted(baxter.joints[name] for name in baxter.limits)
    for target in targets:  # one call, default solver settings, no limits
        reset_arm(baxter, q_home())
        solution = client.calculateInverseKinematics(
            baxter.body, baxter.links[link], target.tolist()
        )
        q = np.array([solution[movable.index(i)] for i in baxter.arm])
        errors.append(np.linalg.norm(kin.fk(q, link=link) - target))
    errors = np.array(errors)
    print(
        f"ik pybullet, 1 call with default settings: within 1 cm {np.mean(errors <= 0.01):.4f}, "
        f"error median {1e3 * np.median(errors):.2f} mm, max {1e3 * errors.max():.1f} mm"
    )
    client.disconnect()


def main(argv: Sequence[str] | None = None) -> int:
    """Run the measurements; return the exit status."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--data", type=Path, help="recorded set, e.g. ../shared/data/birl-handover-20180329"
    )
    parser.add_argument("--targets", type=int, default=2000, help="IK targets (numpy solver)")
    parser.add_argument("--bullet-targets", type=int, default=200, help="IK targets (PyBullet)")
    args = parser.parse_args(argv)
    kin = BaxterKinematics()
    bench_load()
    if args.data is not None:
        count, diff = recorded_fk_offsets(kin, args.data)
        dist = np.linalg.norm(diff, axis=1)
        print(
            f"fk vs recorded baxter_left_hand ({count} trials, {len(diff)} rows): mean "
            f"{1e3 * dist.mean():.2f} mm, max {1e3 * dist.max():.2f} mm, mean offset FK - recorded "
            f"{np.round(1e3 * diff.mean(axis=0), 2)} mm, residual after removing it "
            f"{1e3 * np.linalg.norm(diff - diff.mean(axis=0), axis=1).mean():.2f} mm"
        )
    for link in (TIP_LINK, "left_hand_link"):
        bench_ik(kin, args.targets, link)
    bench_bullet_ik(kin, args.bullet_targets, TIP_LINK)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
