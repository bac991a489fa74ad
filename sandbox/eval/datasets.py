"""Train/test versions of one dataset for leave-one-out evaluation."""

from __future__ import annotations

import warnings


def load_pair(data: str, *, seed: int = 0, tasks=None, n_per_task=None, spec=None,
              observe=None, cache=None, progress: bool = False, session: int | None = None,
              workers: int = 1):
    """The same trials preprocessed for training (smoothed) and as test streams (causal).

    ``data`` is a folder in the shared layout or ``synthetic:NAME``; ``spec`` (a
    :class:`~sandbox.data.spec.DataSpec` or a spec file) and ``observe`` choose
    the modalities (see :func:`sandbox.data.datasets.load_dataset`); ``cache``
    keeps a folder's loaded trials on disk (:mod:`sandbox.data.cache`; ``True``:
    the user's cache folder); ``progress`` draws a bar on stderr; ``session``
    (synthetic sets only) is the recording session's seed; ``workers`` processes preprocess
    a synthetic set's trials (forked, each trial both ways; the same trials). Returns
    ``(train, test, skipped)``; a trial either version cannot use is dropped
    from both, with its reason in ``skipped``.
    """
    from sandbox.data.datasets import load_dataset
    from sandbox.eval.progress import bar, status

    kw = dict(seed=seed, tasks=tasks, n_per_task=n_per_task, spec=spec, observe=observe,
              cache=cache, session=session)
    folder = _n_files(data, tasks)
    if folder is None:
        status(f"generating {data} (training and test versions)", progress)
    with warnings.catch_warnings(record=True) as caught, \
            bar(2 * (folder or 0), "loading", progress and folder is not None) as shown:
        warnings.simplefilter("always")
        kw["on_trial"] = shown.update if folder is not None else None
        if isinstance(data, str) and data.startswith("synthetic"):
            train, test = _synthetic_pair(data, kw, workers)
            more: list[str] = []
        elif folder and workers > 1:
            train, test, more = _folder_pair(data, kw)
            shown.update(2 * folder)      # the workers draw no bar: it fills at the end
        else:
            train = load_dataset(data, preprocess="smooth", **kw)
            test = load_dataset(data, preprocess="causal", **kw)
            more = []
    skipped = sorted({str(w.message) for w in caught} | set(more))
    keep = {d.source for d in train} & {d.source for d in test}
    train = [d for d in train if d.source in keep]
    test = [d for d in test if d.source in keep]
    return train, test, skipped


def _folder_pair(data, kw: dict) -> tuple[list, list, list[str]]:
    """A folder's two versions loaded at once by two forked processes (each version one
    :func:`~sandbox.data.datasets.load_dataset`: the same trials), while this process
    loads numba's kernel, which the leave-one-out's workers then inherit. Returns
    ``(train, test, warnings)``: the workers' warnings (skipped files) as text."""
    from sandbox.core.blendkernel import knots_kernel
    from sandbox.eval.runner import map_trials

    kw = {**kw, "on_trial": None}
    try:
        versions = map_trials(_one_version, 2, _RAW.__setitem__, ("folder", (data, kw)),
                              workers=2, meanwhile=knots_kernel)
    finally:
        _RAW.clear()
    (train, warned_train), (test, warned_test) = versions
    return train, test, warned_train + warned_test


def _one_version(i: int) -> tuple[list, list[str]]:
    """Version ``i`` (0: smooth, 1: causal) of the folder in ``_RAW``, with the text of the
    warnings raised while loading it."""
    from sandbox.data.datasets import load_dataset

    data, kw = _RAW["folder"]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        demos = load_dataset(data, preprocess=("smooth", "causal")[i], **kw)
    return demos, [str(w.message) for w in caught]


def _synthetic_pair(data: str, kw: dict, workers: int = 1) -> tuple[list, list]:
    """A synthetic set generated once, then preprocessed both ways: the same demonstrations
    as two ``load_dataset`` calls (same seed), without generating them twice. With
    ``workers`` > 1 the trials are preprocessed in that many forked processes (the
    generated set is inherited, not sent; each returns its trials both ways)."""
    from sandbox.data.datasets import load_dataset
    from sandbox.eval.runner import map_trials

    raw = load_dataset(data, preprocess="none", **kw)
    pairs = map_trials(_both_ways, len(raw), _RAW.__setitem__, ("demos", raw),
                       workers=workers if len(raw) >= 4 * workers else 1)
    _RAW.clear()
    return [a for a, _ in pairs], [b for _, b in pairs]


#: The generated set :func:`_both_ways` reads (set before the workers fork).
_RAW: dict = {}


def _both_ways(i: int) -> tuple:
    """Trial ``i`` of the generated set, preprocessed for training and as a test stream."""
    from sandbox.data.preprocess import preprocess_demonstration

    demo = _RAW["demos"][i]
    return preprocess_demonstration(demo, "smooth"), preprocess_demonstration(demo, "causal")


def _n_files(data, tasks) -> int | None:
    """Trial files of a folder dataset (None for a synthetic one or a bad folder)."""
    from pathlib import Path

    from sandbox.data.recorded import find_trials

    if not isinstance(data, (str, Path)) or not Path(data).is_dir():
        return None
    try:
        return len(find_trials(data, tasks))
    except ValueError:
        return None
