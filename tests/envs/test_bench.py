"""The environment benchmark functions (figures only checked for shape, never for speed)."""

from __future__ import annotations

import math

from sandbox.bench import env as bench


def test_env_vs_raw_reports_rates_and_their_ratio():
    result = bench.env_vs_raw(n_steps=20, blocks=1)
    assert set(result) == {"env_steps_per_s", "raw_pybullet_steps_per_s", "env_raw_ratio",
                           "env_raw_cpu_ratio", "env_v0_steps_per_s", "env_v1_v0_ratio",
                           "env_reset_ms"}
    assert all(math.isfinite(v) and v > 0 for v in result.values())
    ratio = result["env_steps_per_s"] / result["raw_pybullet_steps_per_s"]
    assert math.isclose(result["env_raw_ratio"], ratio)
    legacy = result["env_steps_per_s"] / result["env_v0_steps_per_s"]
    assert math.isclose(result["env_v1_v0_ratio"], legacy)


def test_policy_steps_per_s_runs_whole_episodes():
    assert bench.policy_steps_per_s(n_episodes=1) > 0


def test_run_env_benchmarks_merges_and_rounds(monkeypatch):
    monkeypatch.setattr(bench, "env_vs_raw", lambda: {"env_steps_per_s": 500.123,
                                                      "raw_pybullet_steps_per_s": 800.0,
                                                      "env_raw_ratio": 0.6251})
    rates = {"baxter": 300.06, "ur5": 200.04}
    monkeypatch.setattr(bench, "policy_steps_per_s",
                        lambda robot="baxter", **kw: rates.get(robot, 1))
    monkeypatch.setattr(bench, "by_robot", lambda: {"baxter": 500.123, "ur5": 700.07})
    assert bench.run_env_benchmarks() == {
        "env_steps_per_s": 500.1, "raw_pybullet_steps_per_s": 800.0, "env_raw_ratio": 0.625,
        "policy_steps_per_s": 300.1,
        "env_steps_per_s_by_robot": {"baxter": 500.1, "ur5": 700.1},
        "policy_steps_per_s_by_robot": {"baxter": 300.1, "panda": 1, "ur5": 200.0, "kinova": 1}}


def test_every_arm_is_timed():
    rates = bench.by_robot(n_steps=10, blocks=1)
    assert list(rates) == ["baxter", "panda", "ur5", "kinova"] and min(rates.values()) > 0
    assert bench.policy_steps_per_s(n_episodes=1, robot="kinova") > 0


def test_soak_reports_memory_and_descriptors_over_steps_and_resets():
    from sandbox.bench.soak import soak

    result = soak(steps=60, reset_every=20)
    assert result["resets"] >= 3 and result["steps"] == 60
    assert [s["step"] for s in result["samples"]] == [0, 6, 12, 18, 24, 30, 36, 42, 48, 54, 60]
    assert all(s["rss_mib"] > 0 and s["fds"] > 0 for s in result["samples"])
    assert result["fd_growth"] == result["samples"][-1]["fds"] - result["samples"][1]["fds"]
    assert result["finite_actions"]


def test_vector_steps_per_s_reports_every_size():
    rates = bench.vector_steps_per_s(sizes=(1, 2), block_s=0.3, blocks=1)
    assert set(rates) == {1, 2}
    assert all(math.isfinite(r) and r > 0 for r in rates.values())


def test_run_vector_benchmarks_reports_the_speedup_of_the_largest_size(monkeypatch):
    monkeypatch.setattr(bench, "vector_steps_per_s", lambda: {1: 100.0, 2: 180.0, 4: 250.04})
    monkeypatch.setattr(bench, "gymnasium_step_per_s", lambda: 99.96)
    result = bench.run_vector_benchmarks()
    assert result["vector_steps_per_s"] == {"1": 100.0, "2": 180.0, "4": 250.0}
    assert result["vector_speedup"] == 2.5
    assert result["gymnasium_benchmark_step_per_s"] == 100.0
    assert len(result["load_average_1min"]) == 2 and result["cpu_count"] >= 1
