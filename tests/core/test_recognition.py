import numpy as np
import pytest

from sandbox.core.recognition import task_posterior


def test_log_space_and_priors():
    post = task_posterior(np.array([-5000.0, -5003.0]), np.array([0.5, 0.5]))
    np.testing.assert_allclose(post, [1 / (1 + np.exp(-3)), np.exp(-3) / (1 + np.exp(-3))])
    post = task_posterior(np.array([0.0, 0.0, 0.0]), np.array([1.0, 0.0, 3.0]))
    np.testing.assert_allclose(post, [0.25, 0.0, 0.75])


def test_errors():
    with pytest.raises(ValueError, match="shape"):
        task_posterior(np.zeros(2), np.ones(3))
    with pytest.raises(ValueError, match="non-negative"):
        task_posterior(np.zeros(2), np.array([1.0, -1.0]))
    with pytest.raises(ValueError, match="NaN"):
        task_posterior(np.array([np.nan, 0.0]), np.ones(2))
