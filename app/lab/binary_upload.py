"""Binary position uploads: raw little-endian floats (``application/octet-stream``) or a
NumPy ``.npy`` file, read straight into arrays (no text parsing, no Python lists).

* raw: ``?dtype=float64`` (default) or ``float32``; ``?columns=2`` for interleaved
  ``time_s, value`` pairs, ``?columns=3`` for ``time_s, value, temperature_c`` triples
  (the bridge, from an instrument that reports its temperature);
* ``.npy`` (recognised by its magic bytes, or sent as ``application/x-npy``): a float or
  integer array of shape ``(n,)`` or ``(n, 1)`` (values), ``(n, 2)`` (``time_s, value``
  rows) or ``(n, 3)`` (``time_s, value, temperature_c``), any byte order, as the lab page
  reads one; never unpickled.
"""

from __future__ import annotations

import numpy as np

from app.core.exceptions import UserError
from app.core.numpy_files import read_npy
from app.lab.store import MAX_SAMPLES_PER_POSITION

NPY_MAGIC = b"\x93NUMPY"
RAW_DTYPES = {
    "float64": "<f8",
    "f8": "<f8",
    "<f8": "<f8",
    "float32": "<f4",
    "f4": "<f4",
    "<f4": "<f4",
}


def is_npy(body: bytes, content_type: str) -> bool:
    return content_type in ("application/x-npy", "application/npy") or body.startswith(NPY_MAGIC)


def _columns(array: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """(values, times) from ``(n,)`` or ``(n, 2)``; finite, not empty, not too many."""
    if array.ndim == 1:
        values, times = array, None
    elif array.ndim == 2 and array.shape[1] == 2:
        times, values = array[:, 0], array[:, 1]
    else:
        raise UserError("api.binary_shape", shape=str(tuple(array.shape)))
    if values.size == 0:
        raise UserError("api.binary_empty")
    if values.size > MAX_SAMPLES_PER_POSITION:
        raise UserError("lab.too_many_samples", limit=MAX_SAMPLES_PER_POSITION)
    if not np.all(np.isfinite(values)):
        raise UserError("api.samples_not_finite")
    if times is not None and not np.all(np.isfinite(times)):
        raise UserError("api.times_not_finite")
    return np.ascontiguousarray(values), None if times is None else np.ascontiguousarray(times)


def parse_npy(body: bytes) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """A ``.npy`` file's values, times and temperatures: float or integer, 1-D or one, two
    (time, value) or three (time, value, temperature) columns."""
    try:
        array = read_npy(body)  # its header checked against its bytes before any allocation
    except ValueError:
        raise UserError("api.bad_npy") from None
    array = array.astype(np.float64, copy=False)
    if array.ndim == 2 and array.shape[1] == 1:  # a column vector: the values
        array = array[:, 0]
    if array.ndim == 2 and array.shape[1] == 3:
        values, times = _columns(array[:, :2])
        return values, times, np.ascontiguousarray(array[:, 2])
    return *_columns(array), None


def parse_raw(
    body: bytes, dtype: str | None, columns: str | None
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """Raw little-endian floats: ``dtype`` float64 (default) or float32, ``columns`` 1, 2
    (time, value) or 3 (time, value, temperature); returns (values, times, temperatures)."""
    code = RAW_DTYPES.get((dtype or "float64").strip().lower())
    if code is None:
        raise UserError("api.bad_dtype", dtype=(dtype or "")[:20])
    width = {"1": 1, "2": 2, "3": 3, None: 1}.get(columns)
    if width is None:
        raise UserError("api.bad_columns")
    item = np.dtype(code).itemsize * width
    if len(body) % item:
        raise UserError("api.binary_length", size=len(body), item=item)
    array = np.frombuffer(body, dtype=code).astype(np.float64, copy=False)  # read-only
    if width == 3:
        rows = array.reshape(-1, 3)
        values, times = _columns(rows[:, :2])
        return values, times, np.ascontiguousarray(rows[:, 2])
    values, times = _columns(array.reshape(-1, 2) if width == 2 else array)
    return values, times, None
