"""Reading arrays from an ``.npz`` archive without trusting it.

``np.load`` reads a member in full before anything can check it, and its
errors suggest ``allow_pickle``. Here an archive is opened only if the file and
its number of members are within :mod:`sandbox.core.limits`, and a member is
read only after its ``.npy`` header (read with
``numpy.lib.format.read_magic`` / ``read_array_header_1_0`` / ``_2_0``) declared
a dtype and shape that the caller expects and that fit the limits: nothing is
allocated for a member before that, and no member that is not asked for is
ever read. Python objects (pickles) are never loaded.

Every problem is an :class:`ArchiveError` (a ``ValueError``) saying what is wrong.
"""

from __future__ import annotations

import os
import struct
import zipfile
import zlib
from math import prod
from pathlib import Path
from typing import Literal

import numpy as np
from numpy.lib import format as npy

from sandbox.core.limits import MAX_MEMBER_BYTES, MAX_MEMBERS, MAX_MODEL_FILE_BYTES

#: What reading a damaged archive can raise besides ``ValueError``.
READ_ERRORS = (zipfile.BadZipFile, zipfile.LargeZipFile, OSError, EOFError, ValueError,
               NotImplementedError, RuntimeError, struct.error, zlib.error, KeyError,
               OverflowError, MemoryError)
_END_OF_DIRECTORY = b"PK\x05\x06"


class ArchiveError(ValueError):
    """A file that is not a readable, well-formed archive within the limits."""


def open_archive(path: Path) -> zipfile.ZipFile:
    """Open ``path`` as a zip archive after checking its size and number of members."""
    size = path.stat().st_size
    if size == 0:
        raise ArchiveError("is empty")
    if size > MAX_MODEL_FILE_BYTES:
        raise ArchiveError(f"has {size} bytes, more than limits.MAX_MODEL_FILE_BYTES="
                           f"{MAX_MODEL_FILE_BYTES}")
    count = _declared_members(path, size)
    if count > MAX_MEMBERS:
        raise ArchiveError(f"declares {count} members, more than limits.MAX_MEMBERS={MAX_MEMBERS}")
    try:
        archive = zipfile.ZipFile(path)
    except READ_ERRORS as error:
        raise ArchiveError(f"is corrupt, truncated or not a .npz archive "
                           f"({type(error).__name__})") from None
    if len(archive.infolist()) > MAX_MEMBERS:
        archive.close()
        raise ArchiveError(f"has more than limits.MAX_MEMBERS={MAX_MEMBERS} members")
    return archive


def _declared_members(path: Path, size: int) -> int:
    """Number of members the end-of-central-directory record declares (0xFFFF: zip64, many)."""
    with open(path, "rb") as fh:
        tail_len = min(size, 22 + 0xFFFF)
        fh.seek(size - tail_len)
        tail = fh.read(tail_len)
    at = tail.rfind(_END_OF_DIRECTORY)
    if at < 0 or len(tail) - at < 22:
        raise ArchiveError("is corrupt, truncated or not a .npz archive (no zip directory)")
    return struct.unpack("<H", tail[at + 10:at + 12])[0]


def read_array(archive: zipfile.ZipFile, name: str, kinds: str,
               shape: tuple[int | None, ...], max_bytes: int = MAX_MEMBER_BYTES) -> np.ndarray:
    """Read member ``name`` (``name.npy``) after checking its header.

    Parameters
    ----------
    archive : zipfile.ZipFile
    name : str
        Member name without ``.npy``.
    kinds : str
        Accepted dtype kinds (``"f"`` floats, ``"U"`` unicode...).
    shape : tuple of int or None
        Expected shape; ``None`` accepts any size on that axis.
    max_bytes : int
        Largest array accepted.

    Returns
    -------
    ndarray
        A writable copy (native byte order).
    """
    try:
        info = archive.getinfo(f"{name}.npy")
    except KeyError:
        raise ArchiveError(f"lacks {[name]}") from None
    try:
        with archive.open(info) as fh:
            dtype, got, order = _header(fh, name)
            _check_header(name, dtype, got, kinds, shape, max_bytes, info.file_size)
            nbytes = prod(got) * dtype.itemsize
            data = fh.read(nbytes)
    except ArchiveError:
        raise
    except READ_ERRORS as error:
        raise ArchiveError(f"member {name!r} is corrupt or truncated "
                           f"({type(error).__name__})") from None
    if len(data) != nbytes:
        raise ArchiveError(f"member {name!r} is truncated: {len(data)} of {nbytes} bytes")
    arr = np.frombuffer(data, dtype=dtype).reshape(got, order=order)
    return arr.astype(dtype.newbyteorder("="), copy=True)


def _header(fh, name: str) -> tuple[np.dtype, tuple[int, ...], Literal["C", "F"]]:
    version = npy.read_magic(fh)
    if version == (1, 0):
        shape, fortran, dtype = npy.read_array_header_1_0(fh)
    elif version == (2, 0):
        shape, fortran, dtype = npy.read_array_header_2_0(fh)
    else:
        raise ArchiveError(f"member {name!r} has .npy format version {version}, not 1.0 or 2.0")
    order: Literal["C", "F"] = "F" if fortran else "C"
    return np.dtype(dtype), tuple(int(n) for n in shape), order


def _check_header(name: str, dtype: np.dtype, got: tuple[int, ...], kinds: str,
                  shape: tuple[int | None, ...], max_bytes: int, member_size: int) -> None:
    if dtype.hasobject or dtype.kind not in kinds:
        raise ArchiveError(f"member {name!r}: expected dtype kind {kinds!r}, got {dtype}"
                           + (" (Python objects are never loaded)" if dtype.hasobject else ""))
    if len(got) != len(shape) or any(w is not None and w != g for w, g in zip(shape, got)):
        want = tuple("n" if w is None else w for w in shape)
        raise ArchiveError(f"inconsistent: member {name!r} has shape {got}, the metadata "
                           f"implies {want}")
    nbytes = prod(got) * dtype.itemsize
    if nbytes > max_bytes:
        raise ArchiveError(f"member {name!r} declares {nbytes} bytes, more than the limit "
                           f"{max_bytes} (limits.MAX_MEMBER_BYTES / MAX_METADATA_BYTES)")
    if nbytes > member_size:
        raise ArchiveError(f"member {name!r} declares {nbytes} bytes but holds {member_size}")


def check_path(path) -> Path:
    """``path`` (str or path-like) as a Path to an existing file."""
    if not isinstance(path, (str, os.PathLike)):
        raise ValueError(f"model file: expected a path (str or os.PathLike), got "
                         f"{type(path).__name__}")
    try:
        path = Path(path)
        ok = path.is_file()
    except (TypeError, ValueError, OSError):
        ok = False
    if not ok:
        raise ValueError(f"model file: expected an existing .npz file, got {str(path)!r}")
    return path
