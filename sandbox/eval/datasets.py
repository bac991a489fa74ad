"""Train/test versions of one dataset for leave-one-out evaluation."""

from __future__ import annotations

import warnings


def load_pair(data: str, *, seed: int = 0, tasks=None, n_per_task=None, spec=None,
              observe=None):
    """The same trials preprocessed for training (smoothed) and as test streams (causal).

    ``data`` is a folder in the shared layout or ``synthetic:NAME``; ``spec`` (a
    :class:`~sandbox.data.spec.DataSpec` or a spec file) and ``observe`` choose
    the modalities (see :func:`sandbox.data.datasets.load_dataset`). Returns
    ``(train, test, skipped)``; a trial either version cannot use is dropped
    from both, with its reason in ``skipped``.
    """
    from sandbox.data.datasets import load_dataset

    kw = dict(seed=seed, tasks=tasks, n_per_task=n_per_task, spec=spec, observe=observe)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        train = load_dataset(data, preprocess="smooth", **kw)
        test = load_dataset(data, preprocess="causal", **kw)
    skipped = sorted({str(w.message) for w in caught})
    keep = {d.source for d in train} & {d.source for d in test}
    train = [d for d in train if d.source in keep]
    test = [d for d in test if d.source in keep]
    return train, test, skipped
