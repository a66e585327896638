"""What a record's column is by its name: the times (by name, unit or word, and their
scale), the case temperature, a counter or a second clock, an acceleration or a field, a
gyro's rates -- and so which columns may hold the rates, the likeliest first.

The names as IMUs, loggers, phones and students write them are listed where each rule is;
one cell's name and unit: :mod:`app.core.column_names`; the layout a header names:
:mod:`app.core.record_columns`.
"""

from __future__ import annotations

import re

from app.core.column_names import (
    ROS_ANGULAR_VELOCITY,
    ColumnName,
    angle_output,
    column_name,
    rate_unit,
)

VALUE_NAMES = ("value", "rate", "omega", "reading", "角速度", "角速率")
TIME_NAMES = ("time", "t", "timestamp", "datetime", "date_time", "sampletimefine", "时间")
TEMPERATURE_NAMES = ("temperature", "temperature_c", "temp", "temp_c", "温度")
TIME_SCALES = {"s": 1.0, "sec": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "μs": 1e-6, "ns": 1e-9}
NAMED_TIME_SCALES = {"sampletimefine": 1e-4}  # Xsens: ticks of 100 µs
# a time column named otherwise: "Elapsed Time (s)", Sensor Logger's "seconds_elapsed",
# "Time since start (ms)", German "Zeit (s)", 历时
TIME_WORDS = re.compile(
    r"(?:^|[^a-z])(?:time|elapsed|zeit|tiempo)(?:$|[^a-z])|时间|时刻|历时", re.IGNORECASE
)
# columns an IMU's record holds beside its rates: counters, stamps, frame names,
# accelerations, magnetic fields, orientations (EuRoC's a_RS_S_x, ROS's
# field.linear_acceleration.x and field.header.seq, Xsens's PacketCounter and Acc_X, a
# STIM's status word, latency and CRC, phyphox's "Absolute" -- the rate vector's length)
NOT_RATE_NAME = re.compile(
    r"seq|count|packet|stamp|frame|status|index|acc(?!um)|(?:^|[^a-z])a_|mag|(?:^|[^a-z])m_"
    r"|quat|orient|covariance|pressure|baro|gps|temp|温度|latency|crc|checksum|valid|flag"
    r"|absolute|magnitude|(?:^|[^a-z])norm(?:$|[^a-z])",  # phyphox's "Absolute": |ω|, no axis
    re.IGNORECASE,
)
TEMPERATURE_WORD = re.compile(r"temp|温度", re.IGNORECASE)
# a column that numbers the readings (not their times): "index", "Sample #", 序号, 采样点
COUNTER_NAME = re.compile(
    r"index|idx|no\.?|n|num|number|#|sample(?:s| no\.?| number| #)?|count(?:er)?|seq"
    r"|序号|点数|采样点|点号|编号|样点|计数|数据点|采样序号",
    re.IGNORECASE,
)
NOT_RATE_UNITS = {"m/s^2", "ms^-2", "m/s2", "m/s²", "g", "mg", "gauss", "ut", "µt", "μt", "nt"}
RATE_NAME = re.compile(
    r"gyr|omega|angular|rate|(?:^|[^a-z])w_|^w[xyz]$|^g[xyz]$|角速", re.IGNORECASE
)


def find_named(names: list[ColumnName], options: tuple[str, ...]) -> int | None:
    """The first column named exactly as one of ``options``, the earlier option first.

    Parameters
    ----------
    names : list of ColumnName
        The header's columns.
    options : tuple of str
        Names (bases, without the unit), the likeliest first.

    Returns
    -------
    int or None
        The column's index from 0, or None where none is so named.
    """
    return next(
        (k for option in options for k, name in enumerate(names) if name.base == option), None
    )


def names_a_time(name: ColumnName) -> bool:
    """Whether a column's name says it holds times.

    Parameters
    ----------
    name : ColumnName
        One column's name and unit.

    Returns
    -------
    bool
        True for one of :data:`TIME_NAMES`, a time's unit ("Zeit (s)", "elapsed_ms"), or a
        time's word beside no rate's unit ("seconds_elapsed", "Elapsed Time").
    """
    return (
        name.base in TIME_NAMES
        or (name.unit or "") in TIME_SCALES
        or bool(TIME_WORDS.search(name.base) and not rate_unit(name.unit))
    )


def time_column(names: list[ColumnName]) -> int | None:
    """The column of a record's times: the first named as :data:`TIME_NAMES` lists, else the
    first whose name says times (:func:`names_a_time`), else none.

    Parameters
    ----------
    names : list of ColumnName
        The header's columns.

    Returns
    -------
    int or None
        The time column's index from 0.
    """
    exact = find_named(names, TIME_NAMES)
    if exact is not None:
        return exact
    return next((k for k, name in enumerate(names) if names_a_time(name)), None)


def only_rate_column(names: list[ColumnName], others: tuple[int | None, ...]) -> int | None:
    """The one column whose unit is a rate's or an angle's ("gyro_z [rad/s]").

    Parameters
    ----------
    names : list of ColumnName
        The header's columns.
    others : tuple of int or None
        Columns already taken (the times, the temperature).

    Returns
    -------
    int or None
        Its index from 0; None where no column or more than one names such a unit.
    """
    found = [
        k
        for k, name in enumerate(names)
        if k not in others and (rate_unit(name.unit) or angle_output(name))
    ]
    return found[0] if len(found) == 1 else None


def rate_column_choices(header: list[str]) -> list[str]:
    """The columns of a header that may hold the rates, the likeliest first: not the times,
    the case temperature or the position; not a counter, a second clock, a stamp, an
    acceleration or a magnetic field (:data:`NOT_RATE_NAME`, :data:`COUNTER_NAME`,
    :data:`NOT_RATE_UNITS`, :data:`TIME_WORDS`) unless nothing else is left; first those
    whose unit is a rate's or an angle's or whose name says rate ("w_RS_S_z", "Gyr_Z",
    "field.angular_velocity.z", "gz").

    Parameters
    ----------
    header : list of str
        The header's cells.

    Returns
    -------
    list of str
        The cells as written (stripped), each a valid ``column`` for
        :func:`app.core.record_columns.header_layout`;
        none where no column's name says rate and there is no time column beside two or
        more others (names of no record).
    """
    names = [column_name(cell) for cell in header]
    time, plausible = plausible_rates(names)
    likely = [k for k in plausible if looks_like_a_rate(names[k])]
    if not likely and (time is None or len(plausible) < 2):
        return []  # names of no record ("hello, world"): nothing to offer
    order = likely + [k for k in plausible if k not in likely]
    return [header[k].strip() for k in order]


def plausible_rates(names: list[ColumnName]) -> tuple[int | None, list[int]]:
    """A header's time column, and the columns that may hold the rates.

    Parameters
    ----------
    names : list of ColumnName
        The header's columns.

    Returns
    -------
    (int or None, list of int)
        The time column (:func:`time_column`); the columns that are not the times, the
        case temperature or the position, nor what :func:`not_a_rate` names -- unless
        nothing else is left, and then never a second clock, a reading's number or a
        temperature ("time, Time (s), sample" has no rates).
    """
    time = time_column(names)
    taken = {time, find_named(names, TEMPERATURE_NAMES), find_named(names, ("position",))}
    free = [k for k in range(len(names)) if k not in taken]
    plausible = [k for k in free if not not_a_rate(names[k])]
    return time, plausible or [k for k in free if not _a_clock_count_or_temperature(names[k])]


def _a_clock_count_or_temperature(name: ColumnName) -> bool:
    return bool(
        names_a_time(name)
        or COUNTER_NAME.fullmatch(name.base)
        or TEMPERATURE_WORD.search(name.base)
        or (name.unit or "").replace(" ", "").lower() in ("°c", "c", "k", "℃")
    )


def not_a_rate(name: ColumnName) -> bool:
    """Whether a column's name says it holds no rates.

    Parameters
    ----------
    name : ColumnName
        One column's name and unit.

    Returns
    -------
    bool
        True for a counter, a second clock ("seconds_elapsed" beside "time"), a stamp, an
        acceleration, a magnetic field, a temperature … (:data:`NOT_RATE_NAME`,
        :data:`COUNTER_NAME`, :data:`NOT_RATE_UNITS`, :func:`names_a_time`).
    """
    unit = (name.unit or "").replace(" ", "")
    return (
        bool(NOT_RATE_NAME.search(name.base) or COUNTER_NAME.fullmatch(name.base))
        or unit in NOT_RATE_UNITS
        or names_a_time(name)
    )


def looks_like_a_rate(name: ColumnName) -> bool:
    """Whether a column's name or unit says it holds a gyro's rates.

    Parameters
    ----------
    name : ColumnName
        One column's name and unit.

    Returns
    -------
    bool
        True for a rate's or an angle's unit, ROS's ``angular_velocity``, or a name such
        as "gyr", "omega", "rate", "w_…", "gz", 角速度 (:data:`RATE_NAME`).
    """
    return bool(
        rate_unit(name.unit)
        or angle_output(name)
        or ROS_ANGULAR_VELOCITY.fullmatch(name.base)
        or RATE_NAME.search(name.base)
    )
