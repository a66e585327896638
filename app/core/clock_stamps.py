"""A record's time column read as seconds: numbers in seconds or in a named unit, a clock
since 1970 in ms, µs or ns told by its size (:func:`epoch_scale`), or a logger's clock --
"2026-11-28 10:00:00.123", ISO 8601 with "T", a "Z" or an offset (one zone for the whole
record), or a time of day ("10:00:00.123"), in other locales' forms too ("2026年11月28日 10:00:00",
"28.11.2026 10:00:00,5", "11/28/2026 10:00:00 AM") -- block by block (:class:`TimeColumn`).  The
records themselves are :mod:`app.core.static_record`.
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
# other locales' clocks, rewritten to the forms above: a Chinese date and time
# ("2026年11月28日 14时05分30秒"), a day or month first ("28.11.2026", "11/28/2026"), a
# 12-hour clock ("2:05:30 PM", "下午 2:05:30")
_CHINESE_DATE = re.compile(r"(\d{4})年(\d{1,2})月(\d{1,2})日?\s*")
_CHINESE_TIME = re.compile(r"(\d{1,2})[时時点](\d{1,2})分(?:(\d{1,2})(?:[.,](\d+))?秒)?")
_YEAR_LAST = re.compile(r"(\d{1,2})([./])(\d{1,2})[./](\d{4})(?=$|[T ])")
_HALF_DAY = re.compile(r"\s*\b(am|pm|a\.m\.|p\.m\.)$|^(上午|下午)\s*|(?<=\s)(上午|下午)\s*", re.I)


def _in_plain_form(text: str) -> str:
    """A clock stamp of another locale in the forms :data:`DATE_TIME` and
    :data:`TIME_OF_DAY` read: "2026年11月28日 14时05分30秒" → "2026-11-28 14:05:30",
    "28.11.2026 14:05:30,5" → "2026-11-28 14:05:30,5", "11/28/2026 2:05:30 PM" →
    "2026-11-28 14:05:30" (a slash: the month first unless the first number is over 12),
    "下午 2:05:30" → "14:05:30"."""
    text = _CHINESE_DATE.sub(
        lambda m: f"{m.group(1)}-{m.group(2)}-{m.group(3)}" + (" " if m.end() < len(text) else ""),
        text,
    )
    text = _CHINESE_TIME.sub(
        lambda m: (
            f"{m.group(1)}:{m.group(2)}:{m.group(3) or '00'}"
            + (f".{m.group(4)}" if m.group(4) else "")
        ),
        text,
    )

    def year_first(m: re.Match) -> str:
        first, separator, second, year = m.groups()
        day_first = separator == "." or int(first) > 12
        month, day = (second, first) if day_first else (first, second)
        return f"{year}-{month}-{day}"

    text = _YEAR_LAST.sub(year_first, text)
    half = _HALF_DAY.search(text)
    if half is None:
        return " ".join(text.split())
    marker = next(group for group in half.groups() if group).lower()
    text = (text[: half.start()] + " " + text[half.end() :]).strip()
    clock = re.search(r"(\d{1,2})(?=:\d{2})", text.split(" ")[-1])
    if clock is None:
        return text
    hour = int(clock.group(1)) % 12 + (12 if marker in ("pm", "p.m.", "下午") else 0)
    head, _, last = " ".join(text.split()).rpartition(" ")
    last = f"{hour:02d}" + last[clock.end() :]
    return f"{head} {last}" if head else last


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
    if DATE_TIME.fullmatch(text) or TIME_OF_DAY.fullmatch(text):
        return True
    text = _in_plain_form(text)
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
        if stamp is None and TIME_OF_DAY.fullmatch(text) is None:
            text = _in_plain_form(text)
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


# the smallest numbers that cannot be seconds (since 1970 or since a record's start: over
# 3,000 years), and the unit since 1970 they are in, by size (true from 1973 to 5138)
EPOCH_SCALES = ((1e17, 1e-9, "ns"), (1e14, 1e-6, "µs"), (1e11, 1e-3, "ms"))


def epoch_scale(first_time: float) -> tuple[float, str] | None:
    """The unit of a time column that names none, from the size of its first number.

    No record's times in seconds reach 1e11 (3,000 years, since 1970 or since its start);
    such numbers are a clock since 1970 in ms (1e11 … 1e14), µs (… 1e17) or ns (beyond),
    true for dates from 1973 to 5138.

    Parameters
    ----------
    first_time : float
        The column's first number.

    Returns
    -------
    (float, str) or None
        Seconds per unit and the unit's name; None for numbers that can be seconds.
    """
    for smallest, scale, name in EPOCH_SCALES:
        if abs(first_time) >= smallest:
            return scale, name
    return None


SPREADSHEET_DAYS = (20_000.0, 80_000.0)  # a spreadsheet's date numbers from 1954 to 2119
SPREADSHEET_DAY_STEP = 5e-5  # days: 4.3 s -- as seconds, a step of 50 µs (20 kHz)


def spreadsheet_days(first: float, step: float) -> bool:
    """Whether a time column that names no unit holds a spreadsheet's date numbers.

    Excel and LibreOffice keep a date and time as days since 1899-12-30 ("46354.5834"
    is 2026-11-28 14:00:05); a column formatted as a number is saved so.  Such numbers lie
    in ``SPREADSHEET_DAYS`` and step by a fraction of a day: at 1 Hz 1.16e-5, at 1 kHz
    1.16e-8.  The same numbers read as seconds would step by at most 50 µs, a gyro logged
    at 20 kHz or more -- none that the lab records.

    Parameters
    ----------
    first : float
        The column's first number.
    step : float
        Its first rise (the first step that is not a tie).

    Returns
    -------
    bool
        True where the column is read as days.
    """
    low, high = SPREADSHEET_DAYS
    return low <= first <= high and 0.0 < step < SPREADSHEET_DAY_STEP


class TimeColumn:
    """A record's time column read block by block, in seconds.

    Numbers in seconds stay as they are; in another unit -- named by the header, or, where
    it names none, told by their size (:func:`epoch_scale`, :func:`spreadsheet_days`) -- they
    are counted from the
    first reading, whole numbers exactly (a clock in ns since 1970 is beyond float64's
    53 bits); a logger's clock stamps (:func:`app.core.clock_stamps.clock_seconds`) are
    read from the midnight of the first date (``clock``: the reader counts them from the
    first reading).
    """

    def __init__(self, scale: float | None) -> None:
        self.scale = scale
        self.clock = False
        self.inferred: str | None = None  # the unit told by the numbers' size
        self._origin: int | float | None = None
        self._origin_day: list[int] = []

    def _unit_of(self, first: float, numbers: np.ndarray | None = None) -> float:
        """The column's unit, decided once, by its first block's numbers."""
        if self.scale is None:
            told = epoch_scale(first)
            if told is None and numbers is not None:
                steps = np.diff(numbers[:1000])
                rising = steps[steps > 0]  # a coarse clock ties its first steps
                if spreadsheet_days(first, float(rising[0]) if rising.size else 0.0):
                    told = (86_400.0, "days")
            self.scale, self.inferred = told if told else (1.0, None)
        return self.scale

    def seconds(self, cells) -> np.ndarray:
        """The block's times in seconds.

        Raises
        ------
        ValueError
            A cell that is neither a number nor a clock stamp.
        """
        try:
            whole = np.asarray(cells, dtype=np.int64)
        except (ValueError, OverflowError):
            whole = None
        if whole is not None and whole.size:
            scale = self._unit_of(float(whole[0]))
            if scale == 1.0:
                return whole.astype(float)
            if self._origin is None:
                self._origin = int(whole[0])
            return (whole - np.int64(self._origin)).astype(float) * scale
        try:
            numbers = np.asarray(cells, dtype=float)
        except ValueError:
            self.clock = True
            return clock_seconds(cells, self._origin_day)
        if not numbers.size:
            return numbers
        scale = self._unit_of(float(numbers[0]), numbers)
        if scale == 1.0:
            return numbers
        if self._origin is None:
            self._origin = float(numbers[0])
        return (numbers - self._origin) * scale

    @staticmethod
    def readable(cell: str) -> bool:
        """Whether one cell is a time (a number or a clock stamp)."""
        try:
            float(cell)
        except ValueError:
            try:
                clock_seconds([cell], [0])
            except ValueError:
                return False
        return True


def spread_within_ticks(times: np.ndarray) -> np.ndarray:
    """Times of a clock coarser than the readings (whole seconds at 10 Hz: ten readings
    share each stamp) spread evenly over each tick, so that they rise.

    A run of ``n`` readings stamped ``t`` before the next stamp ``t'`` is read at
    ``t + k (t' - t) / n``, k = 0 … n-1; the last run at the spacing of the run before
    (one reading per tick where there is none).  Each time moves by less than one tick.

    Parameters
    ----------
    times : numpy.ndarray
        Times that never fall, some repeated.

    Returns
    -------
    numpy.ndarray
        Rising times.
    """
    stamps, starts, counts = np.unique(times, return_index=True, return_counts=True)
    ticks = np.diff(stamps)
    last_tick = ticks[-1] if ticks.size else 1.0
    steps = np.append(ticks, last_tick * counts[-1] / (counts[-2] if counts.size > 1 else 1))
    steps = steps / counts
    within = np.arange(times.size) - np.repeat(starts, counts)
    return times + within * np.repeat(steps, counts)
