"""The observation noise floor a set's own jitter gives, as ``fit`` and ``data summary`` report it.

Each position modality's jitter is measured on the raw tracker frames of every
demonstration (:mod:`sandbox.core.jitter`; the loaders record it before any
filter, ``Demonstration.jitter``) and pooled as the median over demonstrations.
The floor of that modality is ``max(noise_floor, k x jitter)`` with ``k =
jitter_floor`` (a model option, in settings files too; default
:data:`sandbox.core.jitter.JITTER_FACTOR`, 15): the constant ``noise_floor``
(2 cm, chosen by leave-one-out on the recorded handovers, whose jitter of 1.35 mm
gives 20.3 mm) is the documented minimum, and a noisier tracker raises the floor.
``jitter_floor: null`` keeps the constant; ``noise_floor: auto`` searches instead.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from sandbox.core.floorsearch import START_FLOOR
from sandbox.core.jitter import JITTER_FACTOR, demo_jitter


def modality_jitter(demos: Sequence) -> dict[str, float | None]:
    """Median over ``demos`` of each position modality's jitter (m); None if unknown."""
    if not demos:
        return {}
    out: dict[str, list[float]] = {}
    for d in demos:
        values = demo_jitter(d, d.times, np.asarray(d.human, dtype=float), d.modalities)
        start = 0
        for m in d.modalities:
            if m.kind == "position" and np.isfinite(values[start]):
                out.setdefault(m.name, []).append(float(values[start]))
            start += m.size
    names = [m.name for m in demos[0].modalities if m.kind == "position"]
    return {n: (float(np.median(out[n])) if n in out else None) for n in names}


def floor_summary(demos: Sequence, *, noise_floor: float | str = 0.02,
                  jitter_floor: float | None = JITTER_FACTOR,
                  noise_floors: dict | None = None) -> dict[str, dict]:
    """Per position modality: its ``jitter_m``, the ``floor_m`` a model with these options
    uses and where it comes from (``source``), and the floor ``k`` x jitter would give."""
    out = {}
    for name, jitter in modality_jitter(demos).items():
        k = JITTER_FACTOR if jitter_floor is None else jitter_floor
        from_jitter = None if jitter is None else k * jitter
        if noise_floors and name in noise_floors:
            floor, source = float(noise_floors[name]), "noise_floors"
        elif noise_floor == "auto":        # the fit fills floor_m in (sandbox.core.floorsearch)
            floor, source = START_FLOOR, "auto: held-out score on the training demos"
        elif jitter_floor is not None and from_jitter is not None:
            floor = max(float(noise_floor), from_jitter)
            source = f"max(noise_floor {1e3 * float(noise_floor):g} mm, {k:g} x jitter)"
        else:
            floor, source = float(noise_floor), "noise_floor"
        out[name] = {"jitter_m": jitter, "floor_m": floor, "source": source,
                     "k": k, "floor_from_jitter_m": from_jitter}
    return out


def format_floors(summary: dict[str, dict]) -> list[str]:
    """One line per position modality (mm), for the commands' printouts."""
    lines = []
    for name, s in summary.items():
        jitter = "unknown" if s["jitter_m"] is None else f"{1e3 * s['jitter_m']:.2f} mm"
        line = (f"  {name} noise floor {1e3 * s['floor_m']:.1f} mm ({s['source']}); raw jitter "
                f"{jitter}")
        if s["source"] == "noise_floor" and s["floor_from_jitter_m"] is not None:
            line += f"; {s['k']:g} x jitter is {1e3 * s['floor_from_jitter_m']:.1f} mm"
        lines.append(line)
    return lines
