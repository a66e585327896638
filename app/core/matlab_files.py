"""A MATLAB data file (``.mat``, levels 5 to 7: what ``save`` writes by default) holding a
static gyro record, as a record's text: MATLAB's own example of an Allan analysis keeps
its gyro in ``omega`` beside the sample rate ``Fs``, and a lab's scripts keep theirs so.

:func:`matlab_record` reads the file's variables (``scipy.io.loadmat``: numbers only, no
code run) into the static record a text file would give (:mod:`app.core.static_record`):
the readings a vector (or a matrix's column) chosen by its name where there are several,
the times a vector such as ``t`` as long, the sample rate a scalar such as ``Fs`` states
(a struct's fields too: ``imu.gyro``, ``imu.fs``)
(used where no rate is given, as a text file's stated rate is).  A file saved as
``-v7.3`` (HDF5) is refused with how to save it instead.

Reference: The MathWorks, "MAT-File Format" (Level 5: the 128-byte header whose text
starts "MATLAB 5.0 MAT-file"; ``-v7.3``: HDF5, its header "MATLAB 7.3 MAT-file").
"""

from __future__ import annotations

import io

import numpy as np

from app.core.array_files import record_from_variables
from app.core.exceptions import UserError
from app.core.static_record import StaticRecord

LEVEL_5 = b"MATLAB 5.0 MAT-file"
LEVEL_7_3 = b"MATLAB 7.3 MAT-file"
MAX_ELEMENTS = 20_000_000  # numbers in the file's variables, read at most (160 MB)


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
        variables = loadmat(io.BytesIO(data), squeeze_me=True, simplify_cells=True)
    except Exception:
        raise UserError("matlab.unreadable") from None
    return record_from_variables(variables, column, "matlab")
