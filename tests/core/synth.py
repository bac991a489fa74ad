"""Synthetic demonstrations with known answers, made inside the tests (no generator import)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Demo:
    times: np.ndarray
    human: np.ndarray
    robot: np.ndarray
    task: str


def shape(task: int, z: np.ndarray, gain: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Human (T, 3) and robot (T, 7) paths of a task at phases z; tasks end far apart."""
    s = z**3 * (10 - 15 * z + 6 * z**2)
    end = np.array([[0.3, 0.4, 0.0], [0.3, -0.4, 0.0], [0.3, 0.0, 0.4]])[task] * gain
    human = np.array([1.0, 0.0, 0.2]) + s[:, None] * end + 0.05 * np.sin(np.pi * z)[:, None]
    mix = np.linspace(-1, 1, 21).reshape(7, 3)
    robot = 0.5 + s[:, None] * (end @ mix.T) + 0.1 * np.sin(2 * np.pi * z)[:, None]
    return human, robot


def demos(rng: np.random.Generator, n_per_task: int = 10, n_tasks: int = 2,
          duration: float = 2.0, duration_std: float = 0.2, noise: float = 0.002,
          rate: float = 100.0) -> list[Demo]:
    out = []
    for k in range(n_tasks):
        for _ in range(n_per_task):
            T = duration * (1 + duration_std * rng.standard_normal())
            t = np.arange(0, T + 1e-9, 1 / rate)
            h, r = shape(k, t / t[-1], 1 + 0.05 * rng.standard_normal())
            out.append(Demo(t, h + noise * rng.standard_normal(h.shape), r, f"task{k}"))
    return out


def replay(task: int, duration: float, rate: float = 100.0, noise: float = 0.0,
           rng: np.random.Generator | None = None) -> Demo:
    """The task's mean motion replayed at a chosen duration."""
    t = np.arange(0, duration + 1e-9, 1 / rate)
    h, r = shape(task, t / t[-1])
    if noise:
        h = h + noise * rng.standard_normal(h.shape)
    return Demo(t, h, r, f"task{task}")


def fitted_case():
    """A model of 2 tasks (6 demos each, N = 11) and a replay of task 0's first 1.5 s,
    every 5th sample: (model, times (30,), human (30, P))."""
    from sandbox.core.model import IProMP

    rng = np.random.default_rng(0)
    model = IProMP(n_basis=11).fit(demos(rng, n_per_task=6, n_tasks=2, noise=0.003))
    test = replay(0, 2.1, noise=0.003, rng=rng)
    return model, test.times[:150:5], test.human[:150:5]


@dataclass(frozen=True)
class MultiDemo:
    times: np.ndarray
    human: np.ndarray
    robot: np.ndarray
    task: str
    modalities: tuple = ()
    human_names: tuple = ()


def layout():
    """hand (3, position), arm (6, position), emg (4, signal): P = 13."""
    from sandbox.core.modality import Modality

    return (Modality("hand", ("hx", "hy", "hz")),
            Modality("arm", ("ex", "ey", "ez", "sx", "sy", "sz")),
            Modality("emg", ("e0", "e1", "e2", "e3"), "signal"))


def multimodal(rng: np.random.Generator, n_per_task: int = 10, n_tasks: int = 2,
               hand_differs: bool = True, emg_levels=(100.0, 250.0), noise: float = 0.002,
               duration: float = 2.0, rate: float = 100.0) -> list[MultiDemo]:
    """Demos whose hand (optionally the same for all tasks), arm and EMG-like signal are
    known functions of the phase; the signal's level tells the tasks apart (raw units)."""
    mods = layout()
    names = tuple(d for m in mods for d in m.dims)
    out = []
    for k in range(n_tasks):
        for _ in range(n_per_task):
            T = duration * (1 + 0.1 * rng.standard_normal())
            t = np.arange(0, T + 1e-9, 1 / rate)
            z = t / t[-1]
            h, r = shape(k if hand_differs else 0, z, 1 + 0.05 * rng.standard_normal())
            elbow = h + np.array([0.25, 0.1, -0.1]) * (1 - 0.3 * z[:, None])
            shoulder = np.array([1.4, 0.2, 0.35]) + 0.02 * np.sin(np.pi * z)[:, None]
            level = emg_levels[k % len(emg_levels)] * (1 + 0.1 * rng.standard_normal())
            emg = level * (1 + 0.5 * np.sin(np.pi * z))[:, None] * np.array([1, 0.5, 0.8, 1.2])
            human = np.hstack([h, elbow, shoulder, emg])
            human[:, :9] += noise * rng.standard_normal((t.size, 9))
            human[:, 9:] *= 1 + 0.03 * rng.standard_normal((t.size, 4))
            out.append(MultiDemo(t, human, r, f"task{k}", mods, names))
    return out
