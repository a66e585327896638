"""A MATLAB data file (``.mat``, levels 5 to 7: what ``save`` writes by default) holding a
static gyro record: MATLAB's own example of an Allan analysis keeps its gyro in ``omega``
beside the sample rate ``Fs``, and a lab's scripts keep theirs so.

:func:`matlab_record` reads the file's variables (``scipy.io.loadmat``: numbers only, no
code run; in a process of its own, :mod:`app.core.matlab_loader`, since a crafted file can
crash scipy's compiled reader) into the static record a text file would give
(:mod:`app.core.static_record`): the readings a vector (or a matrix's column) chosen by
its name where there are several, the times a vector such as ``t`` as long, the sample
rate a scalar such as ``Fs`` states (a struct's fields too: ``imu.gyro``, ``imu.fs``),
used where no rate is given, as a text file's stated rate is.  A file saved as ``-v7.3``
(HDF5) is refused with how to save it instead.

Reference: The MathWorks, "MAT-File Format" (Level 5: the 128-byte header whose text
starts "MATLAB 5.0 MAT-file"; ``-v7.3``: HDF5, its header "MATLAB 7.3 MAT-file").
"""

from __future__ import annotations

import io

import numpy as np

from app.core.array_files import record_from_variables
from app.core.exceptions import UserError
from app.core.matlab_loader import TOO_LARGE
from app.core.static_record import StaticRecord

LEVEL_5 = b"MATLAB 5.0 MAT-file"
LEVEL_7_3 = b"MATLAB 7.3 MAT-file"
MAX_ELEMENTS = 20_000_000  # numbers in the file's variables, read at most (160 MB)
LOAD_TIMEOUT_S = 120.0  # the loader's own process, at most


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
    return record_from_variables(matlab_variables(data), column, "matlab")


def matlab_variables(data: bytes) -> dict[str, np.ndarray]:
    """The file's numeric variables by name (a struct's fields as ``struct.field``).

    Parameters
    ----------
    data : bytes
        The whole file.

    Returns
    -------
    dict of str to numpy.ndarray
        Each numeric variable, loaded in a process of its own (:mod:`app.core.matlab_loader`).

    Raises
    ------
    UserError
        ``matlab.v73`` for an HDF5 (``-v7.3``) file; ``matlab.unreadable`` for one that is
        not a MATLAB file after all; ``matlab.too_large`` past :data:`MAX_ELEMENTS`.
    """
    if data.startswith(LEVEL_7_3):
        raise UserError("matlab.v73")
    loaded = _load_apart(data)
    with np.load(io.BytesIO(loaded), allow_pickle=False) as arrays:
        return {name: arrays[name] for name in arrays.files}


def _load_apart(data: bytes) -> bytes:
    """The file's numeric variables as a ``.npz``, loaded by scipy in a process of its own
    (:mod:`app.core.matlab_loader`): a file that crashes the loader is refused, never the
    server with it."""
    import subprocess
    import sys

    try:
        done = subprocess.run(
            [sys.executable, "-m", "app.core.matlab_loader", str(MAX_ELEMENTS)],
            input=data,
            capture_output=True,
            timeout=LOAD_TIMEOUT_S,
            check=False,
        )
    except subprocess.TimeoutExpired:
        raise UserError("matlab.unreadable") from None
    if done.returncode == TOO_LARGE:
        raise UserError("matlab.too_large", limit=MAX_ELEMENTS)
    if done.returncode != 0:  # unreadable, or the loader crashed on it
        raise UserError("matlab.unreadable")
    return done.stdout
