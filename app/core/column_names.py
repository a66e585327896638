"""What one header cell of a record says: its name and its unit -- in brackets or
parentheses ("Time (s)", "w_RS_S_z [rad s^-1]"), as the name's suffix ("time_ms",
"rate_deg_h") or after a slash as Chinese tables write it ("时间/s", "角速率/(°/h)") --
whether the unit is a rate's or an angle's, and the text of a comment line that may hold
the header ("#timestamp [ns],…", "%time,…", "// …").  Which column is which:
:mod:`app.core.record_columns`.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from app.core.exceptions import UserError
from app.core.units import DEG_PER_HOUR, DEG_PER_SECOND, RAD_PER_SECOND

COMMENT_MARKS = ("#", "%", "//")
RATE_UNITS = {
    "deg/h": DEG_PER_HOUR,
    "°/h": DEG_PER_HOUR,
    "deg/hr": DEG_PER_HOUR,
    "degh^-1": DEG_PER_HOUR,
    "dph": DEG_PER_HOUR,
    "deg_h": DEG_PER_HOUR,
    "deg/s": DEG_PER_SECOND,
    "°/s": DEG_PER_SECOND,
    "deg/sec": DEG_PER_SECOND,
    "degs^-1": DEG_PER_SECOND,
    "degs-1": DEG_PER_SECOND,
    "dps": DEG_PER_SECOND,
    "deg_s": DEG_PER_SECOND,
    "rad/s": RAD_PER_SECOND,
    "rad/sec": RAD_PER_SECOND,
    "rads^-1": RAD_PER_SECOND,
    "rads-1": RAD_PER_SECOND,
    "rad_s": RAD_PER_SECOND,
    "度/小时": DEG_PER_HOUR,  # as Chinese tables write them
    "度/时": DEG_PER_HOUR,
    "°/小时": DEG_PER_HOUR,
    "°/时": DEG_PER_HOUR,
    "度/秒": DEG_PER_SECOND,
    "°/秒": DEG_PER_SECOND,
    "弧度/秒": RAD_PER_SECOND,
    "rad/秒": RAD_PER_SECOND,
}
# ROS's sensor_msgs/Imu angular velocity, in rad/s by the message's definition (REP 103)
ROS_ANGULAR_VELOCITY = re.compile(r"(?:.*\.)?angular_velocity\.[xyz]")
# an angle per output instead of a rate (KVH's delta angle, Honeywell's and Northrop's Δθ,
# a DSP-3000's integrated angle): the unit of the angle, in degrees
ANGLE_UNITS = {
    "rad": 180.0 / math.pi,
    "mrad": 0.180 / math.pi,
    "urad": 1.8e-4 / math.pi,
    "µrad": 1.8e-4 / math.pi,
    "μrad": 1.8e-4 / math.pi,
    "deg": 1.0,
    "°": 1.0,
    "arcsec": 1.0 / 3600.0,
    "″": 1.0 / 3600.0,
}
INCREMENT_NAME = re.compile(
    r"(?:^|[^a-z])(?:delta|d_?theta|d_?ang(?:le)?|incr(?:ement(?:al)?)?)|[δΔ]|增量", re.IGNORECASE
)
INTEGRATED_NAME = re.compile(r"(integrated|cumulative|累积|积分)", re.IGNORECASE)
_UNIT_IN_BRACKETS = re.compile(r"(.*?)\s*[(\[]([^()\[\]]*)[)\]]")
_TIME_SUFFIX = re.compile(r"(.+?)_(s|ms|us|ns)")
_RATE_SUFFIX = re.compile(r"(.+?)_(deg_h|deg_s|dps|dph|rad_s)")
# "quantity/unit", as ISO 80000-1 and China's GB 3101 head a table's columns ("t/s",
# "时间/s", "角速率/(°/h)", "温度/℃"); never a bare unit ("°/h", "mdeg/s")
_QUANTITY_OVER_UNIT = re.compile(r"([^/]+?)\s*/\s*(.+)")
# an angle's unit as written, with a prefix ("mdeg", "µrad", "度"): a rate's numerator
_ANGLE_UNIT_WORD = r"(?:m|µ|μ|u|k)?(?:deg|degrees?|°|º|˚|rad|arcsec|arcmin|度|弧度|角秒)"
_ANGLE_WORD = re.compile(_ANGLE_UNIT_WORD)
_SLASHED_UNITS = frozenset(
    {"s", "sec", "ms", "us", "µs", "μs", "ns", "h", "min", "秒", "毫秒", "℃", "°c", "c", "k", "度"}
)


@dataclass(frozen=True)
class ColumnName:
    """One header cell: as written (lower case), its name without a unit, and the unit."""

    full: str
    base: str
    unit: str | None


# A spreadsheet's error values (Excel's, LibreOffice's): a cell's failed formula, not a
# comment mark though it starts with "#"
SPREADSHEET_ERRORS = frozenset(
    {
        "#DIV/0!", "#N/A", "#VALUE!", "#REF!", "#NAME?", "#NUM!", "#NULL!", "#SPILL!",
        "#CALC!", "#FIELD!", "#GETTING_DATA", "#BLOCKED!", "#CONNECT!", "#BUSY!",
        "#UNKNOWN!", "#N/A!",
    }
)  # fmt: skip
_FIRST_CELL = re.compile(r"[^,;\t]*")


def is_spreadsheet_error(cell: str) -> bool:
    """Whether a cell is a spreadsheet's error value ("#DIV/0!", "#N/A", "#VALUE!"…).

    Parameters
    ----------
    cell : str
        One cell.

    Returns
    -------
    bool
        True for one of ``SPREADSHEET_ERRORS``, in any case.
    """
    return cell.strip().upper() in SPREADSHEET_ERRORS


def is_hash_comment(line: str) -> bool:
    """Whether a line (or its first cell) is a ``#`` comment: it starts with "#" and is no
    spreadsheet's error value -- a row whose first reading is "#DIV/0!" is a row of
    readings with a problem, never passed over as a comment.

    Parameters
    ----------
    line : str
        A line, or its first cell.

    Returns
    -------
    bool
        True for "# exported by …", False for "#DIV/0!,2.88,…".
    """
    text = line.lstrip()
    return text.startswith("#") and not is_spreadsheet_error(_FIRST_CELL.match(text).group())


def comment_text(text: str) -> str | None:
    """The text of a comment line after its mark (``#``, ``%``, ``//``), or None.

    Parameters
    ----------
    text : str
        A line, stripped.

    Returns
    -------
    str or None
        "timestamp [ns],w_x [rad s^-1]" for "#timestamp [ns],w_x [rad s^-1]".
    """
    if is_spreadsheet_error(_FIRST_CELL.match(text).group()):
        return None  # "#DIV/0!,10.7": a line of readings with a failed formula
    for mark in COMMENT_MARKS:
        if text.startswith(mark):
            return text[len(mark) :].strip()
    return None


def column_name(cell: str) -> ColumnName:
    """A header cell split into its name and its unit.

    Parameters
    ----------
    cell : str
        "Time (s)", "w_RS_S_z [rad s^-1]", "time_ms", "rate_deg_h", "value" ….

    Returns
    -------
    ColumnName
        ("time (s)", "time", "s"), ("w_rs_s_z [rad s^-1]", "w_rs_s_z", "rad s^-1"),
        ("time_ms", "time", "ms"), ("rate_deg_h", "rate", "deg_h"), ("value", "value", None);
        "quantity/unit" as ISO 80000-1 and GB 3101 write it: ("时间/s", "时间", "s"),
        ("角速率/(°/h)", "角速率", "°/h"); a bare unit ("°/h") stays a name.
    """
    full = cell.strip().lower()
    bracketed = _UNIT_IN_BRACKETS.fullmatch(full)
    if bracketed and bracketed.group(1).rstrip(" /"):  # "时间/(s)": the slash is no name's
        return ColumnName(full, bracketed.group(1).rstrip(" /"), bracketed.group(2).strip())
    slashed = _QUANTITY_OVER_UNIT.fullmatch(full)
    if slashed and not _ANGLE_WORD.fullmatch(slashed.group(1)):
        unit = slashed.group(2).strip()
        if (
            unit in _SLASHED_UNITS
            or unit in ANGLE_UNITS
            or rate_unit(unit)
            or RATE_LIKE.fullmatch(unit.replace(" ", ""))
        ):
            return ColumnName(full, slashed.group(1), unit)
    for suffix in (_RATE_SUFFIX, _TIME_SUFFIX):
        named = suffix.fullmatch(full)
        if named:
            return ColumnName(full, named.group(1), named.group(2))
    return ColumnName(full, full, None)


def rate_unit(unit: str | None) -> str | None:
    """The canonical rate unit a column's unit text names ("rad s^-1" → "rad/s"), or None.

    Parameters
    ----------
    unit : str or None
        The unit as written in the header.

    Returns
    -------
    str or None
        "deg/h", "deg/s" or "rad/s"; None when the text names none of them.
    """
    if unit is None:
        return None
    return RATE_UNITS.get(unit.replace(" ", "").replace("·", ""))


# A rate unit as written, read or not: an angle over a time ("mdeg/s", "°/min", "度/分"),
# never a speed ("m/s")
RATE_LIKE = re.compile(_ANGLE_UNIT_WORD + r"\s*/\s*(?:s|sec|h|hr|min|秒|小时|时|分|分钟)")


def readable_rate_unit(unit: str | None) -> str | None:
    """The canonical rate unit a header's unit text names, refusing one GyroLab cannot read.

    Parameters
    ----------
    unit : str or None
        The unit as written in a header or a row of units ("°/s", "mdeg/s").

    Returns
    -------
    str or None
        "deg/h", "deg/s" or "rad/s" as :func:`rate_unit`; None where the text names no
        rate.

    Raises
    ------
    UserError
        ``csv.unit_unread`` where the text names a rate in another unit ("mdeg/s",
        "°/min"): read as one of the three, its readings would be wrong by a factor.
    """
    named = rate_unit(unit)
    if named is None and unit is not None and RATE_LIKE.fullmatch(unit.replace(" ", "").lower()):
        raise UserError("csv.unit_unread", unit=unit.strip()[:20])
    return named


@dataclass(frozen=True)
class AngleOutput:
    """Readings that are angles, not rates: each output's increment Δθ, its integrated
    angle θ, or either (``kind`` None: told from the readings,
    :func:`app.core.angle_outputs.angle_kind`); ``deg_per_unit`` converts them to degrees."""

    kind: str | None  # "increment", "integrated" or None
    deg_per_unit: float
    unit: str  # as the header writes it


def angle_output(name: ColumnName) -> AngleOutput | None:
    """Whether a column's unit is an angle ("dtheta_z [rad]", "Delta angle (deg)"), and
    what kind its name says.

    Parameters
    ----------
    name : ColumnName
        The rates' column.

    Returns
    -------
    AngleOutput or None
        None for a rate or no unit.
    """
    unit = (name.unit or "").replace(" ", "")
    if unit not in ANGLE_UNITS:
        return None
    if INTEGRATED_NAME.search(name.base):
        kind = "integrated"
    elif INCREMENT_NAME.search(name.base):
        kind = "increment"
    else:
        kind = None
    return AngleOutput(kind, ANGLE_UNITS[unit], unit)
