"""A MATLAB data file (``.mat``, levels 5 to 7: what ``save`` writes by default) holding a
static gyro record, as a record's text: MATLAB's own example of an Allan analysis keeps
its gyro in ``omega`` beside the sample rate ``Fs``, and a lab's scripts keep theirs so.

:func:`matlab_record` reads the file's variables (``scipy.io.loadmat``: numbers only, no
code run) into the static record a text file would give (:mod:`app.core.static_record`):
the readings a vector (or a matrix's column) chosen by its name where there are several,
the times a vector such as ``t`` as long, the sample rate a scalar such as ``Fs`` states
(used where no rate is given, as a text file's stated rate is).  A file saved as
``-v7.3`` (HDF5) is refused with how to save it instead.

Reference: The MathWorks, "MAT-File Format" (Level 5: the 128-byte header whose text
starts "MATLAB 5.0 MAT-file"; ``-v7.3``: HDF5, its header "MATLAB 7.3 MAT-file").
"""

from __future__ import annotations

import io
import re

import numpy as np

from app.core.exceptions import UserError
from app.core.record_columns import ColumnChoiceNeeded
from app.core.static_record import StaticRecord

LEVEL_5 = b"MATLAB 5.0 MAT-file"
LEVEL_7_3 = b"MATLAB 7.3 MAT-file"
MAX_ELEMENTS = 20_000_000  # numbers in the file's variables, read at most (160 MB)
MAX_COLUMNS = 8  # a matrix wider than this is no record's columns
_RATE_NAMES = re.compile(
    r"f_?s|fs_?hz|sample_?rate(?:_?hz)?|sampling_?rate|rate_?hz|freq(?:uency)?"
)
_TIME_NAMES = re.compile(r"t|time(?:_?s)?|times?_?s|timestamps?|tt")


def is_matlab_file(magic: bytes) -> bool:
    """Whether a file's first bytes are a MATLAB data file's header (any level).

    Parameters
    ----------
    magic : bytes
        The file's first bytes (20 are enough).

    Returns
    -------
    bool
        True where they start as MATLAB's header text does.
    """
    return magic.startswith((LEVEL_5, LEVEL_7_3))


def matlab_record(data: bytes, column: str | None = None) -> StaticRecord:
    """The file's static record: its readings, its times where a vector such as ``t``
    holds them, the rate a scalar such as ``Fs`` states, and a note naming what was read.

    Parameters
    ----------
    data : bytes
        The whole file.
    column : str, optional
        The readings' vector where the file has several (an IMU's axes: a matrix's
        columns are ``name 1``, ``name 2``, …): its name, or its number from 1 among them.

    Returns
    -------
    StaticRecord
        The readings (in the unit the teacher chooses, else °/h), times, the stated rate,
        and the note ``allan.note_matlab`` (the variable, and the rate's where used).

    Raises
    ------
    UserError
        ``matlab.v73`` for an HDF5 (``-v7.3``) file; ``matlab.unreadable`` for one that is
        not a MATLAB file after all; ``matlab.too_large`` past :data:`MAX_ELEMENTS`;
        ``matlab.no_record`` where no variable is a vector of 16 numbers or more;
        ``matlab.choose_vector`` (a :class:`ColumnChoiceNeeded`, the vectors offered) for
        several and none chosen; ``allan.no_such_column`` for a choice it does not hold.
    """
    from scipy.io import loadmat, whosmat

    if data.startswith(LEVEL_7_3):
        raise UserError("matlab.v73")
    try:
        listed = whosmat(io.BytesIO(data))
    except Exception:  # scipy raises several kinds for a damaged file
        raise UserError("matlab.unreadable") from None
    if sum(int(np.prod(shape)) for _, shape, _ in listed) > MAX_ELEMENTS:
        raise UserError("matlab.too_large", limit=MAX_ELEMENTS)
    try:
        variables = loadmat(io.BytesIO(data), squeeze_me=True)
    except Exception:
        raise UserError("matlab.unreadable") from None
    columns, rate, rate_name = _columns_and_rate(variables)
    if not columns:
        raise UserError("matlab.no_record")
    length = max(values.size for values in columns.values())
    columns = {name: values for name, values in columns.items() if values.size == length}
    time = next((name for name in columns if _TIME_NAMES.fullmatch(name.lower())), None)
    offered = [name for name in columns if name != time]
    if not offered:
        raise UserError("matlab.no_record")
    if column is not None:
        chosen = _chosen(column, offered)
    elif len(offered) > 1:
        raise ColumnChoiceNeeded("matlab.choose_vector", offered, columns=", ".join(offered))
    else:
        chosen = offered[0]
    times = columns[time] if time else None
    said = {"key": "allan.note_matlab", "params": {"variable": chosen}}
    if times is not None:
        said = {"key": "allan.note_matlab_times", "params": {"variable": chosen, "time": time}}
    rate_note = None
    if rate and times is None:  # said where it is used: no times, no rate given
        rate_note = {
            "key": "allan.note_matlab_rate",
            "params": {"name": rate_name, "rate": f"{rate:g}"},
        }
    return StaticRecord(
        columns[chosen],
        times,
        notes=[said],
        stated_rate_hz=rate if times is None else None,
        rate_note=rate_note,
    )


def _chosen(column: str, offered: list[str]) -> str:
    """The vector asked for: its name (any case), or its number from 1 among those offered."""
    wanted = column.strip().lower()
    for name in offered:
        if name.lower() == wanted:
            return name
    if wanted.isdigit() and 1 <= int(wanted) <= len(offered):
        return offered[int(wanted) - 1]
    raise UserError("allan.no_such_column", column=column, columns=", ".join(offered))


def _columns_and_rate(
    variables: dict,
) -> tuple[dict[str, np.ndarray], float | None, str | None]:
    """The file's vectors of real numbers (a matrix's columns each), and the sample rate a
    scalar states with that scalar's name, by the variables' names."""
    columns: dict[str, np.ndarray] = {}
    rate = rate_name = None
    for name, value in variables.items():
        if name.startswith("__"):
            continue
        array = np.asarray(value)
        if array.dtype.kind not in "fiu":
            continue  # text, cells, structs, logicals, complex numbers: no readings
        if array.ndim == 0 or array.size == 1:
            number = float(array.reshape(-1)[0])
            if _RATE_NAMES.fullmatch(name.lower()) and np.isfinite(number) and number > 0:
                rate, rate_name = number, name
            continue
        if array.ndim == 1 and array.size >= 16:
            columns[name] = array.astype(float)
        elif array.ndim == 2 and min(array.shape) <= MAX_COLUMNS and max(array.shape) >= 16:
            matrix = array if array.shape[0] >= array.shape[1] else array.T
            for k in range(matrix.shape[1]):
                columns[f"{name} {k + 1}"] = matrix[:, k].astype(float)
    return columns, rate, rate_name
