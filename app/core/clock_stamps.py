"""A logger's clock in a record's time column: "2026-11-28 10:00:00.123", ISO 8601 with
"T", a "Z" or an offset (one zone for the whole record), or a time of day ("10:00:00.123")
-- read as seconds.  The records themselves are :mod:`app.core.static_record`.
"""

from __future__ import annotations

import re

import numpy as np

DATE_TIME = re.compile(
    r"(\d{4})[-/.](\d{1,2})[-/.](\d{1,2})(?:[T ](\d{1,2}):(\d{2})(?::(\d{2})([.,]\d+)?)?)?"
    r"(?:Z|[+-]\d{2}:?\d{2})?"
)
TIME_OF_DAY = re.compile(r"(\d{1,2}):(\d{2}):(\d{2})([.,]\d+)?")
DAY_S = 86_400.0


def is_clock_stamp(text: str) -> bool:
    """Whether a cell is a date and time or a time of day (a reading, not a name).

    Parameters
    ----------
    text : str
        One cell.

    Returns
    -------
    bool
        True for "2026-11-28 10:00:00.123", "2026/11/28T10:00:00Z", "10:00:00.123" ….
    """
    text = text.strip()
    return bool(DATE_TIME.fullmatch(text) or TIME_OF_DAY.fullmatch(text))


def clock_seconds(cells, origin: list[int]) -> np.ndarray:
    """Seconds of clock stamps: a date and time from the midnight of ``origin``'s day,
    or a time of day from its midnight.

    Parameters
    ----------
    cells : sequence of str
        The stamps, one per reading.
    origin : list of int
        The record's first date (days from 1970-01-01), appended by the first call that
        sees a date and used by every later one, so that blocks of a record share it.

    Returns
    -------
    numpy.ndarray
        Seconds, exact to the stamps' digits (days counted from ``origin``, not 1970).

    Raises
    ------
    ValueError
        A cell that is neither, or an hour, minute or second out of range.
    """
    seconds = np.empty(len(cells))
    days_of: dict[str, int] = {}  # a date repeats on every line of its day
    for index, cell in enumerate(cells):
        text = str(cell).strip()
        stamp = DATE_TIME.fullmatch(text)
        if stamp is not None:
            year, month, day, hour, minute, second, fraction = stamp.groups()
            date = f"{year}-{int(month):02d}-{int(day):02d}"
            days = days_of.get(date)
            if days is None:
                days = days_of[date] = int(np.datetime64(date, "D").astype(np.int64))
                if not origin:
                    origin.append(days)
            days -= origin[0]
        elif (stamp := TIME_OF_DAY.fullmatch(text)) is not None:
            hour, minute, second, fraction = stamp.groups()
            days = 0
        else:
            raise ValueError(f"not a time: {text[:40]!r}")
        if int(hour or 0) > 23 or int(minute or 0) > 59 or int(second or 0) > 60:
            raise ValueError(f"not a time: {text[:40]!r}")
        seconds[index] = (
            days * DAY_S
            + int(hour or 0) * 3600.0
            + int(minute or 0) * 60.0
            + int(second or 0)
            + (float("0." + fraction[1:]) if fraction else 0.0)
        )
    return seconds


def seconds_from_first(times: np.ndarray) -> np.ndarray:
    """A record's clock seconds from its first reading, times of day carried past
    midnight (23:59:59 then 00:00:00 goes on a second, not back a day).

    Parameters
    ----------
    times : numpy.ndarray
        :func:`clock_seconds` of the whole record.

    Returns
    -------
    numpy.ndarray
        Seconds from the first reading.
    """
    if times.max() < DAY_S:  # times of day (or a record within its first day)
        wraps = np.diff(times) < -DAY_S / 2
        if wraps.any():
            times = times + DAY_S * np.concatenate([[0], np.cumsum(wraps)])
    return times - times[0]
