"""How a long table of readings -- one reading per row, beside the position it was read at
-- names its columns.

GyroLab's own export and the serial bridge write ``position,angle_deg,time_s,value``.
Students and their spreadsheets write the same table as "position, rate", "Position,
Reading (°/h)", "angle, rate_deg_h", "位置, 角速度", "转台角度, 读数" -- and for part B
"elevation, rate", "仰角, 读数".  This module maps
such a header to the roles the long layout reads: which column keys the position (its
number or label, or the turntable's angle), which holds the readings, and the optional
times, case temperatures and part.  The layout itself is :mod:`app.core.readings`.
"""

from __future__ import annotations

import re

from app.core.column_names import column_name
from app.core.text_files import plain_text

ROLE_NAMES = {
    "position": (
        "position", "pos", "position no", "position number", "position #", "position index",
        "位置", "位置号", "位置编号", "位置序号",
    ),
    "angle_deg": (
        "angle", "table angle", "turntable angle", "dial angle", "position angle", "dial",
        "dial reading", "刻度", "转台刻度", "刻度盘",
        "elevation", "tilt", "角度", "转台角度", "转角", "位置角", "位置角度", "转台位置角",
        "仰角", "俯仰角", "倾角",
    ),
    "value": (
        "value", "rate", "reading", "output", "gyro", "gyro output", "gyro rate",
        "gyro reading", "omega", "ω", "angular rate", "angular velocity", "measured rate",
        "读数", "角速度", "角速率", "采样值", "输出", "输出值", "陀螺输出", "陀螺读数", "测量值",
    ),
    "time_s": ("time", "t", "时间"),
    "temperature_c": ("temperature", "temp", "温度"),
    "part": ("part",),
}  # fmt: skip
# the units a role may be written in (a time in ms is read as the role "time_ms"; "time
# (min)" is not taken for seconds: not read as the times)
ROLE_UNITS = {
    "angle_deg": {None, "deg", "°", "度", "degree", "degrees"},
    "time_s": {None, "s", "sec", "秒"},
    "temperature_c": {None, "c", "°c", "℃"},
}
MILLISECONDS = {"ms", "毫秒"}
_SUFFIXED_UNIT = re.compile(r"^(.+?) (deg|c)$")  # the rates' and times' own: column_name
_ROLE_OF = {name: role for role, names in ROLE_NAMES.items() for name in names}


def is_value_name(base: str) -> bool:
    """Whether a column's name (its base, without the unit) names a gyro's reading as
    students and loggers write it: "gyro output", "gyro_output", 陀螺输出, 读数.

    Parameters
    ----------
    base : str
        The name as :func:`app.core.column_names.column_name` gives its base.

    Returns
    -------
    bool
        True for a name in ``ROLE_NAMES["value"]``.
    """
    return _ROLE_OF.get(base.replace("_", " ").strip()) == "value"


def name_and_unit(cell: str) -> tuple[str, str | None]:
    """A header cell's name and unit: "Rate (°/h)" → ("rate", "°/h"), "angle_deg" →
    ("angle", "deg"), "time_s" → ("time", "s"), "位置" → ("位置", None).

    Parameters
    ----------
    cell : str
        One cell of the header row.

    Returns
    -------
    tuple of (str, str or None)
        The name in lower case, underscores and runs of spaces as one space; its unit.
    """
    named = column_name(plain_text(cell))  # "Rate (°/h)", "rate_deg_h", "time_s"
    name, unit = re.sub(r"[\s_]+", " ", named.base).strip(), named.unit
    suffixed = _SUFFIXED_UNIT.match(name)
    if suffixed and unit is None and suffixed.group(1) in _ROLE_OF:  # "angle_deg"
        name, unit = suffixed.group(1), suffixed.group(2)
    return name, unit


def long_columns(header: list[str]) -> dict[str, int] | None:
    """The long layout's columns in a header, or None when the header is not one.

    A long header names one column of readings and one that keys each row's position --
    its number or label, or the turntable's angle, or both.  Times (seconds), case
    temperatures (°C) and a ``part`` column are read where named; other columns (a sample
    number, a date) are passed over.  A role named twice, or a time or angle in another
    unit, is not taken as that role.

    Parameters
    ----------
    header : list of str
        The header row's cells.

    Returns
    -------
    dict or None
        Role (``position``, ``angle_deg``, ``value``, ``time_s`` or ``time_ms``,
        ``temperature_c``, ``part``) → column index, or None.
    """
    found: dict[str, list[int]] = {}
    for index, cell in enumerate(header):
        name, unit = name_and_unit(cell)
        role = _ROLE_OF.get(name)
        if role == "time_s" and unit in MILLISECONDS:
            found.setdefault("time_ms", []).append(index)  # "time (ms)": read, in seconds
        elif role is not None and unit in ROLE_UNITS.get(role, {unit}):
            found.setdefault(role, []).append(index)
    roles = {role: indexes[0] for role, indexes in found.items() if len(indexes) == 1}
    if "time_s" in roles and "time_ms" in roles:  # two clocks: neither is the times
        del roles["time_s"], roles["time_ms"]
    if "value" not in roles or not ({"position", "angle_deg"} & roles.keys()):
        return None
    return roles
