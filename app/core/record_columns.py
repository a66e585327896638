"""What a static record's header says: which column holds the rates, the times, the case
temperature and the position, and in which units.

Loggers name their columns in many ways: "value" or "rate_deg_h" (GyroLab and its serial
bridge), "Time (s)" and "Rate (°/h)" (a spreadsheet), "#timestamp [ns]" and
"w_RS_S_z [rad s^-1]" (the EuRoC and Kalibr IMU files, the header behind a comment mark),
"%time" and "field.angular_velocity.z" (ROS's ``rostopic echo -p``), "SampleTimeFine" and
"Gyr_Z" (Xsens MT Manager, ``//`` comments).  A unit in brackets or parentheses, or as
the name's suffix ("time_ms", "rate_deg_h"), is read.  A time column that names no unit
and whose numbers are too large for seconds is read as milliseconds, microseconds or
nanoseconds since 1970 (:func:`epoch_scale`).  What each column is by its name:
:mod:`app.core.column_roles`; the records themselves: :mod:`app.core.static_record`; one
cell's name and unit: :mod:`app.core.column_names`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from app.core.clock_stamps import is_clock_stamp
from app.core.column_names import (
    ROS_ANGULAR_VELOCITY,
    AngleOutput,
    ColumnName,
    angle_output,
    column_name,
    readable_rate_unit,
)
from app.core.column_roles import (
    COUNTER_NAME,
    NAMED_TIME_SCALES,
    TEMPERATURE_NAMES,
    TIME_SCALES,
    VALUE_NAMES,
    find_named,
    not_a_rate,
    only_rate_column,
    plausible_rates,
    rate_column_choices,
    time_column,
)
from app.core.exceptions import UserError
from app.core.long_headers import is_value_name, long_columns
from app.core.table_headers import column_name as position_column_name
from app.core.table_headers import numbered_columns
from app.core.units import RAD_PER_SECOND


class ColumnChoiceNeeded(UserError):
    """A record with several columns that may hold the rates and none chosen (one axis of
    an IMU's record, say).  ``choices``: the columns to offer -- header cells as written,
    or numbers from 1 where there is no header -- the likeliest first."""

    def __init__(self, key: str, choices: list[str], **params: object) -> None:
        super().__init__(key, **params)
        self.choices = choices


@dataclass(frozen=True)
class Layout:
    """Where a record's columns are (0-based) and what their header says of units."""

    value: int
    time: int | None = None
    temperature: int | None = None
    position: int | None = None
    time_scale: float | None = None  # seconds per unit; None: seconds or by size
    rate_unit: str | None = None  # the rates' unit as the header names it
    value_name: str | None = None  # the rates' column as the header names it
    angle: AngleOutput | None = None  # the readings are angles per output, not rates


def chosen_column(column: str, names: list[ColumnName], written: list[str] | None = None) -> int:
    """The column asked for: its header cell, its name without the unit, or its number
    counted from 1.

    Parameters
    ----------
    column : str
        As the user gave it ("w_RS_S_z", "gyr_z", "4").
    names : list of ColumnName
        The header's columns.
    written : list of str, optional
        The header's cells as the file writes them, for the message that lists them
        (default: the names as read, in small letters).

    Returns
    -------
    int
        The column's index from 0.

    Raises
    ------
    UserError
        ``allan.no_such_column``, listing the columns.
    """
    wanted = column.strip().lower()
    for field in ("full", "base"):
        found = [k for k, name in enumerate(names) if getattr(name, field) == wanted]
        if found:
            return found[0]
    if wanted.isdigit() and 1 <= int(wanted) <= len(names):
        return int(wanted) - 1
    raise UserError(
        "allan.no_such_column",
        column=column,
        columns=", ".join(written or [name.full for name in names]) or "1",
    )


def names_a_records_times(header: list[str]) -> bool:
    """Whether a header names a time column among two or more and no position ("Time (ms),
    X_GYRO (deg/s), …", "time,gx,gy,gz", phyphox's and Sensor Logger's): the header of one
    position's record.  A table of positions names its positions ("time, P1, P2 …"),
    numbers them ("时间 | 1 | 2 | 3 | 4", "t | 0° | 90° …"), or has a position column beside
    the times (the long layout, "time_s, position, value").

    Parameters
    ----------
    header : list of str
        A first row's cells.

    Returns
    -------
    bool
        True where two or more cells are filled, one of them names times and none a
        position or the long layout's position or angle.
    """
    cells = [cell for cell in header if cell.strip()]
    if len(cells) < 2 or long_columns(cells) is not None:
        return False
    if numbered_columns(header, more_rows=True) is not None:
        return False  # "时间(s) | 1 | 2 | 3 | 4", "t | 0° | 90° …": positions numbered
    if any(position_column_name(cell).startswith("position_") for cell in cells):
        return False
    return time_column([column_name(cell) for cell in cells]) is not None


def header_layout(header: list[str], column: str | None = None, *, guess: bool = True) -> Layout:
    """The layout a header names.

    Parameters
    ----------
    header : list of str
        The header's cells.
    column : str, optional
        The rates' column, when the record has several (one axis of an IMU's record).
    guess : bool
        Read a header of one to three unknown names as the columns without a header
        (False: refuse it, ``allan.no_value_column``).

    Returns
    -------
    Layout
        By name: the rates ``value`` (or ``rate``, ``omega`` …, or the one ``position_k``),
        the times, the case temperature and the position; a header of one to three
        unknown names is read as the columns without a header.

    Raises
    ------
    UserError
        ``allan.one_position`` for the wide layout of several positions;
        ``allan.no_value_column`` when no column is the rates and none was chosen;
        ``allan.no_rate_column`` when the columns beside the times are none that may be.
    """
    names = [column_name(cell) for cell in header]
    time = time_column(names)
    temperature = find_named(names, TEMPERATURE_NAMES)
    if column is not None:
        value = chosen_column(column, names, [cell.strip() for cell in header])
        position = None
        if time == value:  # the times chosen as the rates: no times beside them
            time = None
    else:
        wide = [k for k, name in enumerate(names) if name.full.startswith("position_")]
        if len(wide) > 1:  # the wide layout: one column per position
            raise UserError("allan.one_position", count=len(wide))
        value = find_named(names, VALUE_NAMES)
        if value is None and wide:
            value = wide[0]
        if value is None:  # the one column whose header names a rate's or an angle's unit
            value = only_rate_column(names, (time, temperature))
        if value is None:  # a gyro's output as students and loggers name it: 陀螺输出, output
            value = next((k for k, name in enumerate(names) if is_value_name(name.base)), None)
        position = find_named(names, ("position",))
        alone = time is not None and position is None  # times beside no position column
        if value is None and alone:  # "time, x": the one column beside the times
            rates = plausible_rates(names)[1]
            value = rates[0] if len(rates) == 1 and not not_a_rate(names[rates[0]]) else None
        if value is None:
            if (
                guess and len(names) <= 3 and time is None
            ):  # unknown names: as without a header, their
                bare = bare_layout(len(names))  # units as the names say
                value, time, temperature = bare.value, bare.time, bare.temperature
                if time is not None and COUNTER_NAME.fullmatch(names[time].base):
                    time = None  # 采样点, "Sample #": a reading's number, not its time
            else:
                choices = rate_column_choices(header)
                raise ColumnChoiceNeeded(
                    "allan.no_rate_column"
                    if not choices and time is not None and (alone or len(names) == 2)
                    # "time, Time (s), sample"; "time, position": no column left for rates
                    else "allan.no_value_column",
                    choices,
                    columns=", ".join(choices or [cell.strip() for cell in header]),
                )
    if time is not None:
        name = names[time]
        scale = NAMED_TIME_SCALES.get(name.base, TIME_SCALES.get(name.unit or ""))
    else:
        scale = None
    return Layout(
        value,
        time,
        temperature if temperature != value else None,
        position,
        scale,
        readable_rate_unit(names[value].unit)
        or (RAD_PER_SECOND if ROS_ANGULAR_VELOCITY.fullmatch(names[value].base) else None),
        header[value].strip(),
        angle_output(names[value]),
    )


def bare_layout(width: int, column: str | None = None) -> Layout:
    """The layout of a record without a header, by its number of columns: the rates;
    time and rate; time, rate and case temperature (the bridge's static record).

    Parameters
    ----------
    width : int
        The record's number of columns.
    column : str, optional
        The rates' column, a number from 1.

    Returns
    -------
    Layout
        Where the rates, times and temperatures are.

    Raises
    ------
    UserError
        ``allan.choose_column`` for four or more columns with none chosen: which is the
        rate cannot be told.
    """
    if column is not None:
        numbers = [ColumnName(str(k), str(k), None) for k in range(1, width + 1)]
        return Layout(chosen_column(column, numbers))
    if width == 1:
        return Layout(0)
    if width == 2:
        return Layout(1, 0)
    if width == 3:
        return Layout(1, 0, 2)
    # no header: any column may be the rates; the first is most often the times
    choices = [str(k) for k in range(2, width + 1)] + ["1"]
    raise ColumnChoiceNeeded("allan.choose_column", choices, count=width)


def bare_record_layout(
    rows: list[list[str]], width: int, column: str | None = None
) -> tuple[Layout, bool]:
    """The layout of a record without a header from its first readings' cells: as
    :func:`bare_layout` says, and -- where the rates' column is chosen -- a first column that
    rises as the times (a FOG logger's ``t, rate, loop, °C``); where none is chosen, a first
    column that does not rise beside one constant column is no times (a KVH DSP-3000's
    ``rate  1``, the 1 its valid flag); a third column of zeros is no case temperature.

    Parameters
    ----------
    rows : list of list of str
        The first readings' cells (the look-ahead).
    width : int
        The record's number of columns.
    column : str, optional
        The rates' column, a number from 1.

    Returns
    -------
    (Layout, bool)
        The layout, and whether its time column was taken from how it rises (to be said,
        and dropped if it falls later).

    Raises
    ------
    UserError
        As :func:`bare_layout`.
    """
    layout = bare_layout(width, column)
    if layout.temperature is not None and _all_zero(rows, layout.temperature):
        layout = replace(layout, temperature=None)  # "t, rate, 0.00000": no sensor's reading
    if layout.time is None and layout.value != 0 and _rises(rows):
        return replace(layout, time=0), True
    if layout.time == 0 and column is None and _falls(rows):
        return _without_times(rows, layout), False
    return layout, False


def _first_numbers(rows: list[list[str]]) -> np.ndarray | None:
    """The first column of ``rows`` as numbers, or None where a cell is not one."""
    try:
        return np.array([float(row[0]) for row in rows])
    except ValueError:
        return None


def _rising(numbers: np.ndarray) -> bool:
    """Never falling, the last after the first: as times are."""
    return bool(np.all(np.diff(numbers) >= 0) and numbers[-1] > numbers[0])


def _rises(rows: list[list[str]]) -> bool:
    """Whether the first column of ``rows`` rises as times do: numbers or clock stamps, in
    at least three rows."""
    if len(rows) < 3:
        return False
    if all(is_clock_stamp(row[0]) for row in rows):
        return True  # the clock's reader checks their order
    numbers = _first_numbers(rows)
    return numbers is not None and _rising(numbers)


def _all_zero(rows: list[list[str]], column: int) -> bool:
    """Whether ``column`` holds 0 in every row (a logger's placeholder where it has no
    temperature sensor), in at least three rows."""
    try:
        return len(rows) >= 3 and all(float(row[column]) == 0.0 for row in rows)
    except ValueError:
        return False


def _falls(rows: list[list[str]]) -> bool:
    """Whether the first column of ``rows`` is numbers that are no times: in at least
    three rows, falling somewhere or never rising."""
    numbers = _first_numbers(rows)
    return numbers is not None and numbers.size >= 3 and not _rising(numbers)


def _without_times(rows: list[list[str]], layout: Layout) -> Layout:
    """A record of two or three columns without a header whose first column does not
    rise: where one column alone varies, it is the rates and there are no times (a KVH
    DSP-3000 writes "rate  1", the 1 a status flag); else the layout as it was, whose
    times are then refused."""
    width = len(rows[0])
    varying = [k for k in range(width) if len({row[k] for row in rows}) > 1]
    return Layout(varying[0]) if len(varying) == 1 else layout
