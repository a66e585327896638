"""A static record out of a file of named arrays -- a MATLAB data file's variables
(:mod:`app.core.matlab_files`), a NumPy ``.npz`` archive's arrays
(:mod:`app.core.numpy_files`): the readings a vector (or a matrix's column) chosen by its
name where there are several, the times a vector such as ``t`` as long, the sample rate a
scalar such as ``Fs`` states -- each said in a note of the file's kind."""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from app.core.exceptions import UserError
from app.core.record_columns import ColumnChoiceNeeded
from app.core.static_record import StaticRecord

MAX_COLUMNS = 8  # a matrix wider than this is no record's columns
MIN_READINGS = 16  # a vector shorter than this is no record
_RATE_NAMES = re.compile(
    r"f_?s|fs_?hz|sample_?rate(?:_?hz)?|sampling_?rate|rate_?hz|freq(?:uency)?"
)
_TIME_NAMES = re.compile(r"t|time(?:_?s)?|times?_?s|timestamps?|tt")


@dataclass(frozen=True)
class ArrayTable:
    """A file's vectors of one length as a table's columns: a matrix's columns are
    ``name 1``, ``name 2``, …; ``time`` the column of times where one is named so; the
    sample rate a scalar such as ``Fs`` states, with that scalar's name."""

    columns: dict[str, np.ndarray]
    time: str | None
    rate_hz: float | None
    rate_name: str | None

    @property
    def offered(self) -> list[str]:
        """The columns that may hold the readings: all but the times."""
        return [name for name in self.columns if name != self.time]


def array_table(variables: dict, kind: str, min_readings: int = MIN_READINGS) -> ArrayTable:
    """The table a file's named arrays hold: its longest vectors (a matrix's columns each,
    vectors of another length passed over), the times among them, the stated rate.

    Parameters
    ----------
    variables : dict
        Name → value (arrays, scalars; anything else is passed over).
    kind : str
        The file's kind, ``matlab`` or ``numpy``: the prefix of its messages' keys.
    min_readings : int
        The fewest numbers a vector (a matrix's longer side) has to be a column: a
        record's for the Allan analysis; fewer for one position's readings on the lab
        page, whose own check then asks for its minimum.

    Returns
    -------
    ArrayTable
        The columns, in the file's order, as float64.

    Raises
    ------
    UserError
        ``<kind>.no_record`` where no array other than the times is a vector of
        ``min_readings`` numbers or more.
    """
    columns, rate, rate_name = _columns_and_rate(variables, min_readings)
    if not columns:
        raise UserError(f"{kind}.no_record")
    length = max(values.size for values in columns.values())
    columns = {name: values for name, values in columns.items() if values.size == length}
    time = next((name for name in columns if _is_time_name(name)), None)
    table = ArrayTable(columns, time, rate, rate_name)
    if not table.offered:
        raise UserError(f"{kind}.no_record")
    return table


def record_from_variables(variables: dict, column: str | None, kind: str) -> StaticRecord:
    """The static record a file's named arrays hold.

    Parameters
    ----------
    variables : dict
        Name → value (arrays, scalars; anything else is passed over).
    column : str, optional
        The readings' vector where there are several (an IMU's axes: a matrix's columns
        are ``name 1``, ``name 2``, …): its name (any case), or its number from 1.
    kind : str
        The file's kind, ``matlab`` or ``numpy``: the prefix of its messages' keys.

    Returns
    -------
    StaticRecord
        The readings, the times where a vector such as ``t`` holds them, the rate a scalar
        such as ``Fs`` states (with the note that says so, where it is used), and the note
        ``allan.note_<kind>`` (or ``…_times``) naming what was read.

    Raises
    ------
    UserError
        ``<kind>.no_record`` where no array is a vector of :data:`MIN_READINGS` numbers or
        more; ``<kind>.choose_vector`` (a :class:`ColumnChoiceNeeded`, the vectors
        offered) for several and none chosen; ``allan.no_such_column`` for a choice that
        is not among them.
    """
    table = array_table(variables, kind)
    offered, time, rate = table.offered, table.time, table.rate_hz
    if column is not None:
        chosen = _chosen(column, offered)
    elif len(offered) > 1:
        raise ColumnChoiceNeeded(f"{kind}.choose_vector", offered, columns=", ".join(offered))
    else:
        chosen = offered[0]
    times = table.columns[time] if time else None
    said = {"key": f"allan.note_{kind}", "params": {"variable": chosen}}
    if times is not None:
        said = {"key": f"allan.note_{kind}_times", "params": {"variable": chosen, "time": time}}
    rate_note = None
    if rate and times is None:  # said where it is used: no times, no rate given
        params = {"name": table.rate_name, "rate": f"{rate:g}"}
        rate_note = {"key": "allan.note_array_rate", "params": params}
    return StaticRecord(
        table.columns[chosen],
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
    variables: dict, min_readings: int
) -> tuple[dict[str, np.ndarray], float | None, str | None]:
    """The vectors of real numbers (a matrix's columns each), and the sample rate a scalar
    states with that scalar's name, by the variables' names."""
    columns: dict[str, np.ndarray] = {}
    rate = rate_name = None
    for name, value in variables.items():
        if name.startswith("__"):
            continue
        last = name.rsplit(".", 1)[-1]  # a struct's field ("imu.fs") by its own name
        try:
            array = np.squeeze(np.asarray(value))
        except (ValueError, TypeError):  # a cell array of unlike parts: no readings
            continue
        if array.dtype.kind not in "fiu":
            continue  # text, cells, structs, logicals, complex numbers: no readings
        if array.ndim == 0 or array.size == 1:
            number = float(array.reshape(-1)[0])
            if _RATE_NAMES.fullmatch(last.lower()) and np.isfinite(number) and number > 0:
                rate, rate_name = number, name
            continue
        if array.ndim == 1 and array.size >= min_readings:
            columns[name] = array.astype(float)
        elif (
            array.ndim == 2 and min(array.shape) <= MAX_COLUMNS and max(array.shape) >= min_readings
        ):
            matrix = array if array.shape[0] >= array.shape[1] else array.T
            for k in range(matrix.shape[1]):
                columns[f"{name} {k + 1}"] = matrix[:, k].astype(float)
    return columns, rate, rate_name


def _is_time_name(name: str) -> bool:
    """Whether a vector's name (a struct's field by its own) is a time's: t, time, …"""
    return _TIME_NAMES.fullmatch(name.rsplit(".", 1)[-1].lower()) is not None
