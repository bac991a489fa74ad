"""Gaussian basis functions over the phase z in [0, 1] (paper eq. 1 and 3).

Notation: N basis functions with centres :math:`c_n` and common width
:math:`h`,

.. math::  \\psi_n(z) = \\exp\\left(-\\frac{(z - c_n)^2}{2h}\\right),

optionally normalised so that :math:`\\sum_n \\psi_n(z) = 1`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from sandbox.core.limits import MAX_BASIS_WIDTH, MAX_N_BASIS, MIN_BASIS_WIDTH
from sandbox.validation import (
    FloatArray,
    check_array,
    check_bool,
    check_integer,
    check_number,
)


@dataclass(frozen=True)
class GaussianBasis:
    """N Gaussian bumps over phase.

    Parameters
    ----------
    n_basis : int
        Number of basis functions N, 2 to :data:`~sandbox.core.limits.MAX_N_BASIS`.
        The paper uses 31.
    width : float or None
        Variance h of each bump (phase units squared), within
        [:data:`~sandbox.core.limits.MIN_BASIS_WIDTH`,
        :data:`~sandbox.core.limits.MAX_BASIS_WIDTH`]. ``None``: the squared
        spacing between centres, so neighbours cross at exp(-1/8) of their peak.
    margin : float
        Centres are spread evenly over ``[-margin, 1 + margin]``.
    normalized : bool
        Divide by the sum over bumps (a partition of unity).
    """

    n_basis: int = 31
    width: float | None = None
    margin: float = 0.0
    normalized: bool = False
    _centers: FloatArray = field(init=False, repr=False, compare=False)
    _neg_half_h: float = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        n = check_integer(self.n_basis, "n_basis", 2, MAX_N_BASIS)
        width = None if self.width is None else check_number(
            self.width, "width", low=MIN_BASIS_WIDTH, high=MAX_BASIS_WIDTH)
        margin = check_number(self.margin, "margin", low=0.0)
        if margin >= 1:
            raise ValueError(f"margin: expected a number in [0, 1), got {self.margin!r}")
        object.__setattr__(self, "n_basis", n)
        object.__setattr__(self, "width", width)
        object.__setattr__(self, "margin", margin)
        object.__setattr__(self, "normalized", check_bool(self.normalized, "normalized"))
        # the hot path's constants, computed once (evaluate runs at every update)
        object.__setattr__(self, "_centers", self.centers)
        object.__setattr__(self, "_neg_half_h", -0.5 / self.h)

    @property
    def centers(self) -> FloatArray:
        """Centres :math:`c_n`, shape (N,)."""
        return np.linspace(-self.margin, 1.0 + self.margin, int(self.n_basis))

    @property
    def h(self) -> float:
        """The variance h actually used."""
        if self.width is not None:
            return float(self.width)
        spacing = (1.0 + 2.0 * self.margin) / (self.n_basis - 1)
        return spacing**2

    def __call__(self, z: ArrayLike) -> FloatArray:
        """Evaluate the basis.

        Parameters
        ----------
        z : array_like, shape (...)
            Phases (usually in [0, 1]).

        Returns
        -------
        Psi : ndarray, shape (..., N)
            :math:`\\psi_n(z)` for every phase (eq. 3 rows).
        """
        z = np.asarray(z, dtype=np.float64)
        return self.evaluate(z)

    def evaluate(self, z: FloatArray) -> FloatArray:
        """Like ``__call__`` without conversion (hot path; ``z`` is a float array)."""
        d = z[..., None] - self._centers           # eq. 3: row t of Psi is psi(z_t)^T
        e = d * d * self._neg_half_h
        if not self.normalized:
            return np.exp(e)
        e -= e.max(axis=-1, keepdims=True)   # stable far outside [0, 1]
        psi = np.exp(e)
        psi /= psi.sum(axis=-1, keepdims=True)
        return psi

    def to_dict(self) -> dict:
        """JSON-serialisable parameters."""
        return {
            "n_basis": int(self.n_basis),
            "width": None if self.width is None else float(self.width),
            "margin": float(self.margin),
            "normalized": bool(self.normalized),
        }

    @classmethod
    def from_dict(cls, d: dict) -> GaussianBasis:
        """Inverse of :meth:`to_dict`; a ``ValueError`` for anything else."""
        keys = {"n_basis", "width", "margin", "normalized"}
        if not isinstance(d, dict) or not set(d) <= keys:
            got = sorted(map(str, set(d) - keys)) if isinstance(d, dict) else type(d).__name__
            raise ValueError(f"basis: expected a mapping with keys among {sorted(keys)}, got {got}")
        return cls(**d)


def design_matrix(basis: GaussianBasis, z: ArrayLike) -> FloatArray:
    """Checked version of ``basis(z)`` for 1-D phases: returns Psi of shape (T, N)."""
    z = check_array(z, "z", 1)
    return basis.evaluate(z)
