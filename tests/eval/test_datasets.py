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


def test_a_folder_pair_loaded_by_two_workers_is_the_one_process_pair(tmp_path):
    """Each version loaded in its own forked process: the same trials and the same skipped
    files (their warnings come back from the workers as text)."""
    from tests.commands.test_data_cli import write_trial

    root = tmp_path / "set"
    for task, end_z in (("low", 0.05), ("high", 0.35)):
        for i in range(3):
            write_trial(root / task / f"trial{i}.csv", seed=i, end_z=end_z)
    (root / "low" / "broken.csv").write_text("t,human_left_hand_x\n")
    one = load_pair(str(root), cache=False, workers=1)
    two = load_pair(str(root), cache=False, workers=2)
    assert two[2] == one[2] and len(one[2]) == 1 and "broken.csv" in one[2][0]
    for got, want in zip(two[:2], one[:2]):
        assert [d.source for d in got] == [d.source for d in want] and len(got) == 6
        for a, b in zip(got, want):
            for name in ("times", "human", "robot"):
                np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
            assert a.task == b.task and a.meta.keys() == b.meta.keys()
