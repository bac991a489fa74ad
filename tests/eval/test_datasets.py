"""sandbox/eval/datasets.py: the train/test versions of a set."""

import numpy as np
import pytest

from sandbox.data.datasets import load_dataset
from sandbox.eval.datasets import load_pair


@pytest.mark.parametrize("workers", [1, 2])
def test_a_synthetic_pair_is_each_version_as_loaded_on_its_own(workers):
    """Also when two forked workers preprocess the trials (10 trials: both take some)."""
    train, test, skipped = load_pair("synthetic:diverging", n_per_task=2, seed=3, session=1,
                                     workers=workers)
    for got, how in ((train, "smooth"), (test, "causal")):
        want = load_dataset("synthetic:diverging", n_per_task=2, seed=3, session=1,
                            preprocess=how)
        assert [d.source for d in got] == [d.source for d in want] and len(got) == 10
        for a, b in zip(got, want):
            for name in ("times", "human", "robot"):
                np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
            assert a.task == b.task and a.meta.keys() == b.meta.keys()
    assert skipped == []
