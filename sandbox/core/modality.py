"""Observation modalities: named groups of human dims, each with a kind, units and noise.

An observation of the human is a set of modalities (DESIGN.md, "Observation
modalities"): the hand (the paper's setup), the same-side elbow and shoulder,
the forearm's muscle activity, or a user's own. Each :class:`Modality` names
its dims (for recorded data: the CSV columns), its kind and its units:

``"position"``
    Tracked positions (m). Observation noise is floored at the model's
    ``noise_floor``; the values are used as they come.
``"signal"``
    A non-negative activity signal such as an EMG envelope (raw units). The
    model divides it by a per-dim scale fitted on its training demonstrations
    only (``IProMP.scale``), and floors its noise at
    ``signal_floor`` in those normalised units.

The human dims of a model are the concatenation of its modalities' dims, in
order, so P = sum of their sizes. A row of observations may lack a modality
(NaN in any of its dims): that modality is then unobserved at that time, its
rows of H are masked (eq. 9), never filled in.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

KINDS = ("position", "signal")
#: Units of each kind when a modality does not say.
DEFAULT_UNITS = {"position": "m", "signal": "raw"}


@dataclass(frozen=True)
class Modality:
    """A named group of observed human dims.

    Parameters
    ----------
    name : str
        E.g. ``"hand"``, ``"arm"``, ``"emg"``.
    dims : sequence of str
        Names of its dims (for recorded data, the CSV columns), at least one.
    kind : {"position", "signal"}
        How it is preprocessed and normalised (module docstring).
    units : str, optional
        Units of the values as they come (default by kind: m or raw).
    """

    name: str
    dims: tuple[str, ...]
    kind: str = "position"
    units: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.strip() or "," in self.name:
            raise ValueError(f"modality name: expected a non-empty name without commas, "
                             f"got {self.name!r}")
        if isinstance(self.dims, str):
            raise ValueError(f"modality {self.name!r}: expected a sequence of dim names, "
                             f"got the string {self.dims!r}")
        dims = tuple(self.dims)
        if not dims or not all(isinstance(d, str) and d for d in dims):
            raise ValueError(f"modality {self.name!r}: expected non-empty dim names, got {dims!r}")
        if len(set(dims)) != len(dims):
            raise ValueError(f"modality {self.name!r}: dim names repeat in {dims!r}")
        if not isinstance(self.kind, str) or self.kind not in KINDS:
            raise ValueError(f"modality {self.name!r}: kind expected one of {list(KINDS)}, "
                             f"got {self.kind!r}")
        object.__setattr__(self, "dims", dims)
        object.__setattr__(self, "units", str(self.units or DEFAULT_UNITS[self.kind]))

    @property
    def size(self) -> int:
        """Number of dims."""
        return len(self.dims)

    def to_dict(self) -> dict:
        """JSON-ready description (inverse: :meth:`from_dict`)."""
        return {"name": self.name, "dims": list(self.dims), "kind": self.kind,
                "units": self.units}

    @classmethod
    def from_dict(cls, d: dict) -> Modality:
        """Build from :meth:`to_dict`'s output."""
        if not isinstance(d, dict):
            raise ValueError(f"modality: expected a mapping, got {type(d).__name__}")
        unknown = set(d) - {"name", "dims", "kind", "units"}
        if unknown:
            raise ValueError(f"modality: unknown keys {sorted(unknown)}")
        dims = d.get("dims", ())
        if isinstance(dims, str) or not isinstance(dims, (list, tuple)):
            raise ValueError(f"modality: expected a list of dim names, got {dims!r}")
        units = d.get("units", "")
        if not isinstance(units, str):
            raise ValueError(f"modality: expected units as a string, got {units!r}")
        return cls(d.get("name", ""), tuple(dims), d.get("kind", "position"), units)


def default_modalities(names: Sequence[str]) -> tuple[Modality, ...]:
    """One position modality ``"hand"`` over all human dims: the paper's setup."""
    return (Modality("hand", tuple(names), "position", "m"),)


def check_modalities(modalities: Sequence[Modality], n_dims: int | None = None
                     ) -> tuple[Modality, ...]:
    """Validate a modality layout: distinct names, distinct dims, sizes adding up to ``n_dims``."""
    mods = tuple(modalities)
    if not mods or not all(isinstance(m, Modality) for m in mods):
        raise ValueError(f"modalities: expected at least one Modality, got {modalities!r}")
    names = [m.name for m in mods]
    if len(set(names)) != len(names):
        raise ValueError(f"modalities: names repeat in {names}")
    dims = [d for m in mods for d in m.dims]
    twice = sorted({d for d in dims if dims.count(d) > 1})
    if twice:
        raise ValueError(f"modalities: dims {twice} belong to more than one modality")
    if n_dims is not None and len(dims) != n_dims:
        raise ValueError(f"modalities: expected {n_dims} human dims in all, got {len(dims)} "
                         f"({', '.join(f'{m.name}: {m.size}' for m in mods)})")
    return mods


def slices(modalities: Sequence[Modality]) -> dict[str, slice]:
    """Each modality's slice of the concatenated human dims."""
    out, start = {}, 0
    for m in modalities:
        out[m.name] = slice(start, start + m.size)
        start += m.size
    return out


def modality_index(modalities: Sequence[Modality]) -> np.ndarray:
    """Index of the modality of every human dim, shape (P,)."""
    return np.repeat(np.arange(len(modalities)), [m.size for m in modalities])


def select(modalities: Sequence[Modality], names: Sequence[str] | str | None,
           what: str = "observe") -> tuple[Modality, ...]:
    """The modalities named in ``names`` (a list or ``"a,b"``), in the order given.

    ``None`` selects all. An unknown name is a ``ValueError`` listing what there is.
    """
    mods = tuple(modalities)
    if names is None:
        return mods
    if isinstance(names, str):
        names = [n.strip() for n in names.split(",") if n.strip()]
    try:
        names = list(names)
    except TypeError:
        raise ValueError(f"{what}: expected modality names (a list or 'a,b'), got "
                         f"{type(names).__name__}") from None
    if not all(isinstance(n, str) for n in names):
        raise ValueError(f"{what}: expected modality names (strings), got {names!r}")
    have = {m.name: m for m in mods}
    unknown = [n for n in names if n not in have]
    if unknown or not names:
        raise ValueError(f"{what}: expected names among {list(have)}, got "
                         f"{unknown if unknown else names}")
    if len(set(names)) != len(names):
        raise ValueError(f"{what}: names repeat in {names}")
    return tuple(have[n] for n in names)
