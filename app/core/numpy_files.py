"""A static gyro record saved by NumPy, as a lab's Python scripts keep one: a ``.npy``
array (``np.save``) -- the readings ``(n,)``, or rows of ``time_s, value`` ``(n, 2)`` or
``time_s, value, temperature_c`` ``(n, 3)``, the REST API's layouts -- or a ``.npz``
archive of named arrays (``np.savez``), read as a MATLAB file's variables are
(:mod:`app.core.array_files`: ``omega`` beside ``fs``, ``t``, an IMU's matrix).  Read with
``allow_pickle=False``: an object array is refused, never unpickled.

Reference: NumPy Enhancement Proposal 1, "A simple file format for NumPy arrays" (the
magic ``\\x93NUMPY``; ``.npz``: a zip of ``.npy`` files).
"""

from __future__ import annotations

import io
import zipfile

import numpy as np

from app.core.array_files import record_from_variables
from app.core.exceptions import UserError
from app.core.static_record import StaticRecord

NPY_MAGIC = b"\x93NUMPY"
MAX_ELEMENTS = 20_000_000  # numbers in the file's arrays, read at most (160 MB)


def is_npy(magic: bytes) -> bool:
    """Whether a file's first bytes are a ``.npy`` array's.

    Parameters
    ----------
    magic : bytes
        The file's first bytes (6 are enough).

    Returns
    -------
    bool
        True where they are NumPy's magic string.
    """
    return magic.startswith(NPY_MAGIC)


def is_npz(data: bytes) -> bool:
    """Whether a file is a ``.npz`` archive: a zip whose members are all ``.npy`` arrays.

    Parameters
    ----------
    data : bytes
        The whole file.

    Returns
    -------
    bool
        True for a zip of ``.npy`` members only (an Excel workbook is a zip of XML).
    """
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as archive:
            names = archive.namelist()
    except Exception:  # any zip the module cannot open (a damaged one, "zip file version 8.5")
        return False
    return bool(names) and all(name.endswith(".npy") for name in names)


def numpy_record(data: bytes, column: str | None = None) -> StaticRecord:
    """The static record a ``.npy`` array or a ``.npz`` archive holds.

    Parameters
    ----------
    data : bytes
        The whole file.
    column : str, optional
        For a ``.npz`` of several vectors: the readings' one, by its name or its number.

    Returns
    -------
    StaticRecord
        The readings, their times and case temperatures where the array has those
        columns (``.npy``), or as :func:`app.core.array_files.record_from_variables`
        reads a ``.npz``; a note naming what was read.

    Raises
    ------
    UserError
        ``numpy.unreadable`` for a damaged file, an object array or one of text;
        ``numpy.too_large`` past :data:`MAX_ELEMENTS`; ``numpy.shape`` for a ``.npy``
        of another shape; those of :func:`app.core.array_files.record_from_variables`.
    """
    loaded = numpy_arrays(data)
    if isinstance(loaded, dict):
        return record_from_variables(loaded, column, "numpy")
    return _array_record(loaded)


def numpy_arrays(data: bytes) -> np.ndarray | dict[str, np.ndarray]:
    """A ``.npy`` file's array, or a ``.npz`` archive's arrays by name.

    Parameters
    ----------
    data : bytes
        The whole file.

    Returns
    -------
    numpy.ndarray or dict of str to numpy.ndarray
        The array (``.npy``); the arrays by name (``.npz``).  Never unpickled.

    Raises
    ------
    UserError
        ``numpy.unreadable`` for a damaged file or a pickle; ``numpy.too_large`` for an
        archive whose arrays unpack past :data:`MAX_ELEMENTS` numbers.
    """
    try:
        loaded = np.load(io.BytesIO(data), allow_pickle=False)
    except Exception:  # NumPy raises several kinds for a damaged file or a pickle
        raise UserError("numpy.unreadable") from None
    if not isinstance(loaded, np.lib.npyio.NpzFile):
        return loaded
    with loaded:
        # the members' sizes unpacked, from the zip's directory: nothing loaded yet
        unpacked = sum(member.file_size for member in loaded.zip.infolist())
        if unpacked > 8 * MAX_ELEMENTS + 4096 * len(loaded.files):
            raise UserError("numpy.too_large", limit=MAX_ELEMENTS)
        try:
            return {name: loaded[name] for name in loaded.files}
        except Exception:
            raise UserError("numpy.unreadable") from None


def _array_record(array: np.ndarray) -> StaticRecord:
    """A ``.npy``'s record: ``(n,)`` readings; ``(n, 2)`` times and readings; ``(n, 3)``
    with case temperatures (the REST API's layouts)."""
    if array.size > MAX_ELEMENTS:
        raise UserError("numpy.too_large", limit=MAX_ELEMENTS)
    if array.dtype.kind not in "fiu":
        raise UserError("numpy.unreadable")
    array = array.astype(float)
    if array.ndim == 1 and array.size:
        return StaticRecord(array, notes=[{"key": "allan.note_npy", "params": {}}])
    if array.ndim == 2 and array.shape[1] in (2, 3) and array.shape[0]:
        temperatures = array[:, 2] if array.shape[1] == 3 else None
        key = "allan.note_npy_temperatures" if temperatures is not None else "allan.note_npy_times"
        note = {"key": key, "params": {}}
        return StaticRecord(array[:, 1], array[:, 0], temperatures, notes=[note])
    raise UserError("numpy.shape", shape=str(tuple(array.shape)))
