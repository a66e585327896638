"""What a static record says above its first reading -- a header (fitted to the
readings' columns where spaces split names with spaces), a row of units under it, a
comment line naming the columns (EuRoC's, Kalibr's, ROS's) -- and the layout decided from
it, or from the first lines' numbers where it says nothing.  The record is read by
:mod:`app.core.static_record`; which column is which: :mod:`app.core.record_columns`."""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass, replace

from app.core.clock_stamps import is_clock_stamp
from app.core.column_names import comment_text, readable_rate_unit
from app.core.exceptions import UserError
from app.core.record_columns import Layout, bare_record_layout, header_layout
from app.core.spreadsheet_text import is_units_row

# "Device: DSP-1750", "Sample rate: 2 Hz", "采样率：10 Hz": a logger's lines about the record
# above its table -- a name that starts with a letter, then a colon and a space or the next
# cell ("Device:,DSP-1750": a spreadsheet's two cells; a clock's "14:00:00" starts with a
# digit and has none)
_ABOUT_THE_RECORD = re.compile(r"[^\W\d_][^:：,;\t]{0,40}(?::[\s,;]|：|:$)")


def describes_the_record(text: str) -> bool:
    """Whether a line above a record's table says something about it ("Device: DSP-1750",
    "Date: 2026-11-28 14:00", "采样率：10 Hz") rather than naming its columns.

    Parameters
    ----------
    text : str
        One line, stripped.

    Returns
    -------
    bool
        True for a name that starts with a letter and is followed by a colon and a space
        (or a full-width colon).
    """
    return _ABOUT_THE_RECORD.match(text) is not None


_STATED_RATE = re.compile(
    r"(?:sample|sampling|output|data)?\s*(?:rate|frequency)|采样率|采样频率|输出频率|数据率",
    re.IGNORECASE,
)
_HERTZ = re.compile(r"([0-9]+(?:\.[0-9]+)?)\s*(k?hz|sps)\b", re.IGNORECASE)


def stated_rate_hz(text: str) -> float | None:
    """The sample rate a line about the record states ("Sample rate: 2 Hz", "采样率：10Hz",
    "Output rate: 1 kHz"), or None.

    Parameters
    ----------
    text : str
        A line :func:`describes_the_record`.

    Returns
    -------
    float or None
        The rate (Hz) where the line's name is a rate's and its value a number of hertz.
    """
    parts = re.split(r"[:：]", text, maxsplit=1)
    if len(parts) < 2 or not _STATED_RATE.fullmatch(parts[0].strip()):
        return None
    value = parts[1]
    hertz = _HERTZ.search(value)
    if hertz is None:
        return None
    rate = float(hertz.group(1)) * (1000.0 if hertz.group(2).lower() == "khz" else 1.0)
    return rate if rate > 0 else None


def is_header(cells: list[str]) -> bool:
    """Whether a line's cells are names.

    Parameters
    ----------
    cells : list of str
        One line's cells.

    Returns
    -------
    bool
        True where one cell at least is neither a number nor a clock stamp.
    """
    return any(cell.strip() and not _is_number(cell) and not is_clock_stamp(cell) for cell in cells)


def _look_ahead_rows(
    lines: list[str], split: Callable[[str], list[str]], width: int
) -> list[list[str]]:
    """The cells of the readings among ``lines`` (the look-ahead) that have ``width``."""
    rows = []
    for raw in lines:
        text = raw.strip().lstrip("\ufeff")
        if text and comment_text(text) is None and len(cells := split(text)) == width:
            rows.append(cells)
    return rows


def holds_a_number(cells: list[str]) -> bool:
    """Whether a line holds a reading.

    Parameters
    ----------
    cells : list of str
        One line's cells.

    Returns
    -------
    bool
        True where one cell at least is a number.
    """
    return any(_is_number(cell) for cell in cells)


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def _fitted_header(cells: list[str], text: str, width: int) -> list[str] | None:
    """The header's cells for ``width`` columns of readings: as split, or -- where spaces
    split the columns and the names have spaces -- a unit in brackets joined to its name
    ("Time (s)  Rate (deg/h)"), or the whole line as the one column's name; None when
    they cannot match."""
    if len(cells) == width:
        return cells
    joined: list[str] = []
    for word in text.split():
        if joined and word[:1] in "([":
            joined[-1] += " " + word
        else:
            joined.append(word)
    if len(joined) == width:
        return joined
    return [text] if width == 1 else None


def header_in_comment(comment: str | None, split, width: int) -> list[str] | None:
    """A header written as the comment line just above the readings ("#timestamp [ns],
    w_x [rad s^-1], …", "%time,field.angular_velocity.x, …").

    Parameters
    ----------
    comment : str or None
        The last comment line's text, after its mark.
    split : callable
        The record's splitter of a line into cells.
    width : int
        The readings' number of columns.

    Returns
    -------
    list of str or None
        Its cells, where it has ``width`` of them (two at least) and they are names.
    """
    if comment is None or width < 2:
        return None
    cells = split(comment)
    return cells if len(cells) == width and is_header(cells) else None


@dataclass
class Preamble:
    """What a record says above its first reading: a header, the row of units under it,
    and the last comment line (which may be the header: EuRoC's, ROS's)."""

    header: list[str] | None = None  # the header's cells, once seen
    header_text: str = ""
    units_next: bool = False  # the line after a header may name the units
    units: list[str] | None = None  # that line's cells, where it does
    comment: str | None = None  # the last comment line before the readings
    comment_line: int = 0

    def takes_units(self, cells: list[str]) -> bool:
        """Whether ``cells``, the line after the header, only name units (kept)."""
        if not self.units_next:
            return False
        self.units_next = False
        if is_units_row(cells):
            self.units = cells
            return True
        return False

    def takes_header(self, cells: list[str], text: str, split) -> bool:
        """Whether ``cells`` are the header (kept, read at the readings' width): the first
        line of names, where no comment above names the readings' columns."""
        named = header_in_comment(self.comment, split, len(cells))
        if self.header is None and named is None and is_header(cells):
            self.header, self.header_text, self.units_next = cells, text, True
            return True
        return False

    def layout(
        self, cells: list[str], line: int, first: list[str], split, column, guess: bool
    ) -> tuple[Layout, bool, list[dict]]:
        """The record's layout, decided at its first line of readings (``cells``, at
        ``line``): from the header, else a comment naming the columns, else the first
        lines' numbers; whether the first column was taken for the times; the notes."""
        width = len(cells)
        if self.header is not None:
            header = _fitted_header(self.header, self.header_text, width)
            if header is None:
                raise UserError("allan.bad_line", line=line)
            layout = header_layout(header, column, guess=guess)
            if (
                layout.rate_unit is None
                and self.units is not None
                and layout.value < len(self.units)
            ):
                # the rates' unit in the row of units under the names, not in the name
                unit = readable_rate_unit(self.units[layout.value].lower())
                layout = replace(layout, rate_unit=unit)
            return layout, False, []
        named = header_in_comment(self.comment, split, width)
        if named is not None and holds_a_number(cells):  # a ROS frame's name, say
            note = {"key": "allan.note_comment_header", "params": {"line": self.comment_line}}
            return header_layout(named, column, guess=guess), False, [note]
        layout, guessed = bare_record_layout(_look_ahead_rows(first, split, width), width, column)
        return layout, guessed, []
