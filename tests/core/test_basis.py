import numpy as np
import pytest

from sandbox.core.basis import GaussianBasis, design_matrix


def test_peaks_at_centres_and_shape():
    basis = GaussianBasis(11)
    psi = basis(basis.centers)
    assert psi.shape == (11, 11)
    np.testing.assert_allclose(np.diag(psi), 1.0)
    assert np.all(np.argmax(psi, axis=1) == np.arange(11))


def test_width_default_is_squared_spacing():
    basis = GaussianBasis(5)
    assert basis.h == pytest.approx(0.25**2)
    z = np.array([0.125])  # halfway between centres 0 and 0.25
    np.testing.assert_allclose(basis(z)[0, :2], np.exp(-0.125**2 / (2 * 0.0625)))


def test_normalized_is_partition_of_unity():
    psi = GaussianBasis(9, normalized=True)(np.linspace(0, 1, 50))
    np.testing.assert_allclose(psi.sum(axis=1), 1.0)


def test_round_trip_dict():
    b = GaussianBasis(7, width=0.01, margin=0.1, normalized=True)
    assert GaussianBasis.from_dict(b.to_dict()) == b


@pytest.mark.parametrize("kwargs", [{"n_basis": 1}, {"n_basis": 2.5}, {"width": -1.0},
                                    {"margin": 1.5}, {"width": np.nan}])
def test_bad_parameters(kwargs):
    with pytest.raises(ValueError):
        GaussianBasis(**kwargs)


def test_design_matrix_checks_input():
    with pytest.raises(ValueError, match="1-D"):
        design_matrix(GaussianBasis(5), np.zeros((2, 2)))
    with pytest.raises(ValueError, match="NaN"):
        design_matrix(GaussianBasis(5), [0.1, np.nan])
