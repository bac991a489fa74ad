"""The observation stream a predictor keeps: which modalities, normalised, subsampled.

A predictor observes some or all of its model's modalities
(:mod:`sandbox.core.modality`). :class:`ObservationStream` maps each incoming
row onto the model's human dims (NaN for modalities not observed), divides
signal modalities by the model's scale, and keeps 1 of every ``subsample``
valid samples *of each modality* (as the paper keeps 1 of every 5). A modality
is valid in a row when all its dims are finite; a NaN in it (a dropout) masks
that modality in that row only. A row with no valid modality is skipped.

A modality whose values lie outside the range the model was fitted on, widened
by a generous margin (:func:`observation_bounds`), is rejected: counted in
:attr:`ObservationStream.n_rejected` and masked like a NaN, so one wild value (a
tracker glitch of 1e153) can never reach the likelihood of this or any later
window. At most :data:`~sandbox.core.limits.MAX_OBSERVATIONS` rows are kept.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from sandbox.core.limits import (
    MAX_OBSERVATIONS,
    MAX_SUBSAMPLE,
    POSITION_MARGIN_M,
    SIGNAL_MARGIN,
)
from sandbox.core.modality import Modality, select, slices
from sandbox.core.promp import trajectory_distribution
from sandbox.validation import FloatArray, check_array, check_integer

if TYPE_CHECKING:
    from sandbox.core.model import IProMP

#: Phases at which :func:`observation_bounds` evaluates the tasks.
_RANGE_PHASES = np.linspace(0.0, 1.0, 101)


def observation_bounds(model: IProMP) -> tuple[FloatArray, FloatArray]:
    """Range of accepted human values, in the model's normalised units.

    The range the model was fitted on is derived from the model itself (old
    model files have it too): over every task and phase, the mean of each human
    dim +/- 3 standard deviations of the task's trajectory distribution. It is
    widened by :data:`~sandbox.core.limits.POSITION_MARGIN_M` (10 m) for
    position modalities and :data:`~sandbox.core.limits.SIGNAL_MARGIN` (1e3 x
    the training demos' standard deviation) for signal modalities.

    Returns
    -------
    low, high : ndarray, shape (P,)
    """
    P = int(model.n_human)
    low, high = np.full(P, np.inf), np.full(P, -np.inf)
    for task in model.task_models:
        mean, cov = trajectory_distribution(task.weights.dims(slice(0, P)), model.basis,
                                            _RANGE_PHASES)
        sd = 3.0 * np.sqrt(np.maximum(np.diagonal(cov, axis1=1, axis2=2), 0.0))
        low = np.minimum(low, (mean - sd).min(axis=0))
        high = np.maximum(high, (mean + sd).max(axis=0))
    position = np.array([m.kind == "position" for m in model.modalities for _ in m.dims])
    margin = np.where(position, POSITION_MARGIN_M / np.asarray(model.scale, dtype=np.float64),
                      SIGNAL_MARGIN)
    return low - margin, high + margin


class ObservationStream:
    """Observations received so far, in the model's human layout.

    Parameters
    ----------
    model : IProMP
        A fitted model.
    observe : sequence of str or str, optional
        Modalities the incoming rows carry, in this order (default: all of the
        model's). A name the model was not fitted with is a ``ValueError``.
    subsample : int
        Keep 1 of every ``subsample`` valid samples of each modality (1 to
        :data:`~sandbox.core.limits.MAX_SUBSAMPLE`).

    Attributes
    ----------
    n_skipped : int
        Rows skipped because no modality was valid in them (NaN or rejected).
    n_rejected : int
        Rows in which a modality was rejected as outside :attr:`bounds`.
    bounds : tuple of ndarray, shape (P,)
        :func:`observation_bounds` of the model (normalised units).
    """

    def __init__(self, model: IProMP, observe: Sequence[str] | str | None = None,
                 subsample: int = 5) -> None:
        subsample = check_integer(subsample, "subsample", 1, MAX_SUBSAMPLE)
        self.modalities: tuple[Modality, ...] = tuple(model.modalities)
        self.observed = select(self.modalities, observe,
                               f"observe (this model has {[m.name for m in self.modalities]})")
        where = slices(self.modalities)
        self._index = {m.name: i for i, m in enumerate(self.modalities)}
        self._cols = np.concatenate([np.arange(where[m.name].start, where[m.name].stop)
                                     for m in self.observed])
        self._dims = [np.arange(where[m.name].start, where[m.name].stop)
                      for m in self.modalities]
        self._starts = np.array([where[m.name].start for m in self.modalities])
        self.scale = np.asarray(model.scale, dtype=np.float64)
        self.n_human = int(model.n_human)
        self.subsample = subsample
        self.bounds = observation_bounds(model)
        self.reset()

    @property
    def size(self) -> int:
        """Number of values an incoming row carries (the observed modalities' dims)."""
        return int(self._cols.size)

    def reset(self) -> None:
        """Forget every observation."""
        self._n = 0                    # kept rows: the first _n of the buffers (append-only)
        self._t = np.empty(64)
        self._y = np.empty((64, self.n_human))
        self._valid = np.zeros(len(self.modalities), dtype=int)
        self.n_skipped = 0
        self.n_rejected = 0

    def row(self, y) -> FloatArray:
        """One incoming row as the model's human dims (normalised units, NaN if unobserved).

        ``y`` is an array of :attr:`size` values (the observed modalities' dims in
        order) or a mapping from observed modality names to their values.
        """
        full = np.full(self.n_human, np.nan)
        if isinstance(y, Mapping):
            names = [m.name for m in self.observed]
            unknown = [k for k in y if k not in names]
            if unknown:
                raise ValueError(f"y: expected modalities among {names}, got {unknown}")
            where = slices(self.modalities)
            for m in self.observed:
                if m.name in y:
                    s = where[m.name]
                    full[s] = check_array(y[m.name], f"y[{m.name!r}]", 1, shape=(m.size,),
                                          allow_nan=True)
        else:
            values = check_array(y, "y", 1, allow_nan=True)
            if values.size != self.size:
                layout = ", ".join(f"{m.name} ({m.size})" for m in self.observed)
                raise ValueError(f"y: expected {self.size} values ({layout}), got {values.size}")
            full[self._cols] = values
        return full / self.scale

    def accept(self, t: float, y) -> FloatArray | None:
        """Take a row received at ``t`` (s); return what is kept of it, or None.

        The kept row has NaN for every modality not kept (not observed, NaN in
        the row, outside :attr:`bounds`, or dropped by the subsampling).
        Raises ``ValueError`` once :data:`~sandbox.core.limits.MAX_OBSERVATIONS`
        rows are kept.
        """
        if self._n >= MAX_OBSERVATIONS:
            raise ValueError(f"observations: this predictor keeps {self._n} observations, "
                             f"the most it may (limits.MAX_OBSERVATIONS); reset() it between "
                             f"motions or raise subsample")
        full = self.row(y)
        low, high = self.bounds
        finite = np.isfinite(full)
        valid = np.logical_and.reduceat(finite, self._starts)
        inside = np.logical_and.reduceat(finite & (full >= low) & (full <= high), self._starts)
        if np.any(valid & ~inside):
            self.n_rejected += 1
            valid = inside
        if not valid.any():
            self.n_skipped += 1
            return None
        keep = valid & (self._valid % self.subsample == 0)
        self._valid += valid
        if not keep.any():
            return None
        for i in np.flatnonzero(~keep):
            full[self._dims[i]] = np.nan
        if self._n == self._t.size:        # grown by doubling: new buffers, the old unchanged
            self._t = np.concatenate([self._t, np.empty(self._n)])
            self._y = np.concatenate([self._y, np.empty(self._y.shape)])
        self._t[self._n], self._y[self._n] = t, full
        self._n += 1
        return full

    def observations(self) -> tuple[FloatArray, FloatArray]:
        """Kept observations: times (s,) and values (s, P), normalised, NaN where unobserved."""
        return self._t[:self._n].copy(), self._y[:self._n].copy()

    def until(self, t: float) -> tuple[FloatArray, FloatArray]:
        """The kept observations at times <= ``t`` (s), as read-only views (an update's
        window: no copy; rows once kept are never written again)."""
        n = int(np.searchsorted(self._t[:self._n], t, side="right"))   # times never decrease
        times, values = self._t[:n], self._y[:n]
        times.flags.writeable = values.flags.writeable = False
        return times, values

    @property
    def first_time(self) -> float:
        """Time (s) of the first kept observation; inf before any."""
        return float(self._t[0]) if self._n else float("inf")

    def __len__(self) -> int:
        return self._n
