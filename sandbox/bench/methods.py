"""Benchmark of every method's update (``python -m sandbox bench --methods``).

The core benchmark's reference case (:func:`sandbox.bench.core.reference_case`:
4 synthetic tasks of 20 demos, P = 3, Q = 7, N = 31, the first 2 s of a
held-out motion at 100 Hz, 1 kept in 5), streamed through each method of
:data:`sandbox.methods.METHODS` with an update every 0.2 s, on one BLAS thread.
``<method>_update_ms`` is the median wall time per update of the ``observe``
calls since the previous update (what the filters of BIP and eBIP spend on
each observation included, as ``compare`` measures it), over ``streams``
streams; ``<method>_update_multimodal_ms`` the same with P = 17 (hand, arm,
EMG; :func:`sandbox.bench.core.reference_case` with ``multimodal``).
"""

from __future__ import annotations

import time

import numpy as np

from sandbox.bench.core import reference_case


def update_times(predictor, times, human) -> list[float]:
    """Seconds of the ``observe`` calls per update while streaming ``times, human``."""
    out, spent = [], 0.0
    for t, y in zip(times, human):
        start = time.perf_counter()
        upd = predictor.observe(t, y)
        spent += time.perf_counter() - start
        if upd is not None:
            out.append(spent)
            spent = 0.0
    return out


def run_method_benchmarks(streams: int = 3, seed: int = 0) -> dict:
    """Median update time (ms) of every method, P = 3 and P = 17 (module docstring)."""
    from sandbox.methods import METHODS, DemoLibrary, make_predictor

    result = {}
    for suffix, multimodal in (("", False), ("_multimodal", True)):
        model, times, human, train = reference_case(seed, multimodal=multimodal,
                                                    with_demos=True)
        library = DemoLibrary.from_demos(model, train)
        for name in METHODS:
            pred = make_predictor(name, library, dow_t=0.2, expected_duration=2.0)
            seconds = []
            for _ in range(max(1, streams)):
                pred.reset()
                seconds += update_times(pred, times, human)
            result[f"{name}_update{suffix}_ms"] = round(1e3 * float(np.median(seconds)), 3)
    return result
