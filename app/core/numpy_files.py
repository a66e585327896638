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


def read_npy(data: bytes) -> np.ndarray:
    """A ``.npy`` file's array of numbers, its header checked against its bytes first.

    ``np.load`` allocates the array its header claims before it reads the data: 200 bytes
    claiming 10¹² numbers raised MemoryError, 10⁹ numbers set 8 GB aside.  Here the header
    (NEP 1: magic, version, a Python literal of ``descr``, ``fortran_order``, ``shape``) is
    read alone, the array must be real numbers that its bytes hold whole, and the numbers
    are viewed where they lie (``np.frombuffer``: no copy, never unpickled).

    Parameters
    ----------
    data : bytes
        The whole file.

    Returns
    -------
    numpy.ndarray
        The array (read-only, in the file's byte order), of float, signed or unsigned
        integer numbers.

    Raises
    ------
    ValueError
        For a header that cannot be read (any version but 1.0 and 2.0), another kind of
        data (text, complex, dates, records, objects), or fewer bytes than it claims.
    """
    stream = io.BytesIO(data)
    try:
        version = np.lib.format.read_magic(stream)
        if version == (1, 0):
            shape, fortran_order, dtype = np.lib.format.read_array_header_1_0(stream)
        elif version == (2, 0):
            shape, fortran_order, dtype = np.lib.format.read_array_header_2_0(stream)
        else:
            raise ValueError(f"version {version}")
    except Exception as error:  # a header NumPy cannot parse (ValueError, a TokenError, …)
        raise ValueError("not a .npy header") from error
    if dtype.kind not in "fiu" or dtype.hasobject:
        raise ValueError(f"not numbers: {dtype}")
    if any(length < 0 for length in shape):  # NumPy's header reader lets (-5,) through
        raise ValueError(f"shape {shape}")
    count = 1
    for length in shape:
        count *= length
    if count * dtype.itemsize > len(data) - stream.tell():
        raise ValueError("fewer bytes than the header claims")
    flat = np.frombuffer(data, dtype=dtype, count=count, offset=stream.tell())
    return flat.reshape(shape, order="F" if fortran_order else "C")


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
    if is_npy(data[:6]):
        try:
            return read_npy(data)
        except ValueError:
            raise UserError("numpy.unreadable") from None
    try:
        loaded = np.load(io.BytesIO(data), allow_pickle=False)
    except Exception:  # NumPy raises several kinds for a damaged file or a pickle
        raise UserError("numpy.unreadable") from None
    if not isinstance(loaded, np.lib.npyio.NpzFile):
        raise UserError("numpy.unreadable")
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
