"""Train/test versions of one dataset for leave-one-out evaluation."""

from __future__ import annotations

import warnings


def load_pair(spec: str, *, seed: int = 0, tasks=None, n_per_task=None):
    """The same trials preprocessed for training (smoothed) and as test streams (causal).

    ``spec`` is a folder in the shared layout or ``synthetic:NAME`` (see
    :func:`sandbox.data.datasets.load_dataset`).
    """
    from sandbox.data.datasets import load_dataset

    kw = dict(seed=seed, tasks=tasks, n_per_task=n_per_task)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        train = load_dataset(spec, preprocess="smooth", **kw)
        test = load_dataset(spec, preprocess="causal", **kw)
    skipped = sorted({str(w.message) for w in caught})
    keep = {d.source for d in train} & {d.source for d in test}
    train = [d for d in train if d.source in keep]
    test = [d for d in test if d.source in keep]
    return train, test, skipped
