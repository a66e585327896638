"""LabVIEW's measurement file (``.lvm``, written by its "Write To Measurement File"), the
text record a university lab's data-acquisition program most often keeps: a file header
and a segment header, each closed by ``***End_of_Header***``, then a line naming the
columns (``X_Value``, the channels, ``Comment``) and the readings.

:func:`labview_lines` passes the headers over (as blank lines, so that every line keeps
its number), names the ``X_Value`` column a time in seconds where the segment says its X
is time, drops the empty ``Comment`` column, and keeps what the headers state: the sample
period ``Delta_X`` (the rate, where the file has no X column).

Reference: National Instruments, "LabVIEW Measurement File (.lvm) Format", the file and
segment header fields (``Separator``, ``Decimal_Separator``, ``X_Columns``,
``X_Dimension``, ``Delta_X``, ``***End_of_Header***``).
"""

from __future__ import annotations

import contextlib
import re
from collections.abc import Iterable, Iterator
from dataclasses import dataclass

SIGNATURE = "LabVIEW Measurement"
END_OF_HEADER = "***End_of_Header***"
_FIELD = re.compile(r"([^\t,;]+)[\t,;]+([^\t,;]*)")


def is_labview_measurement(start: str) -> bool:
    """Whether a file starts with the signature of LabVIEW's measurement file.

    Parameters
    ----------
    start : str
        The file's beginning (blank lines and a byte-order mark before it allowed).

    Returns
    -------
    bool
        True where it starts with ``LabVIEW Measurement``.
    """
    return start.lstrip().lstrip("\ufeff").lstrip().startswith(SIGNATURE)


@dataclass
class LabviewHeaders:
    """What the headers said, filled in as :func:`labview_lines` reads them: the lines
    they took (first and last), the X column's dimension and presence, the sample period."""

    first_line: int = 0
    last_line: int = 0  # of the headers before the first reading
    segments: int = 0  # segment headers read (a file of several segments repeats them)
    x_columns: str = "One"  # "No", "One" or "Multi"
    x_dimension: str = "Time"
    delta_x: float | None = None

    @property
    def rate_hz(self) -> float | None:
        """The sample rate 1/Delta_X where the X is time and the period positive."""
        if self.delta_x is None or self.delta_x <= 0 or self.x_dimension.lower() != "time":
            return None
        return 1.0 / self.delta_x

    def take(self, number: int, text: str) -> None:
        """Note one header line (its number and its field)."""
        self.first_line = self.first_line or number
        if text.startswith("Channels"):
            self.segments += 1
        if self.segments <= 1:
            self.last_line = number
        field = _FIELD.match(text.strip())
        if field is None:
            return
        name, value = field.group(1).strip(), field.group(2).strip()
        if name == "X_Columns":
            self.x_columns = value or self.x_columns
        elif name == "X_Dimension":
            self.x_dimension = value or self.x_dimension
        elif name == "Delta_X" and self.delta_x is None:
            with contextlib.suppress(ValueError):  # a period that is no number: none stated
                self.delta_x = float(value.replace(",", "."))


def labview_lines(lines: Iterable[str], headers: LabviewHeaders) -> Iterator[str]:
    """The file's lines with its headers blank, its column line named as a record's.

    Parameters
    ----------
    lines : iterable of str
        The file's lines, from its first.
    headers : LabviewHeaders
        Filled in with what the headers say, as they are read.

    Returns
    -------
    iterator of str
        Each line: "" for a header's (and a later segment's repeated column line), the
        column line with ``X_Value`` as ``time (s)`` (X in time) and without ``Comment``,
        and the readings as they are.
    """
    in_header = True  # the file header comes first
    expect_columns = False  # the line after a header names the columns
    column_line: str | None = None
    for number, raw in enumerate(lines, 1):
        text = raw.strip().lstrip("\ufeff")
        if not in_header and text.startswith("Channels"):  # a segment's header begins
            in_header = True
        if in_header:
            headers.take(number, text)
            if text.startswith(END_OF_HEADER):
                in_header, expect_columns = False, True
            yield "\n"
            continue
        if not text.strip("\t,; "):  # blank, or only the separator (",": a comma file's)
            yield "\n"
            continue
        if expect_columns:
            expect_columns = False
            if column_line is None:
                column_line = text
                yield _named_columns(text, headers) + "\n"
            else:
                yield "\n"  # a later segment's column line, as the first's
            continue
        yield raw


def _named_columns(text: str, headers: LabviewHeaders) -> str:
    """The column line as a record names its columns: the first ``X_Value`` a time in
    seconds (where X is time), the empty ``Comment`` column dropped, and a lone channel
    that LabVIEW named ``Untitled`` the record's ``value``."""
    separator = next((mark for mark in "\t,;" if mark in text), "\t")  # the file's own
    cells = [cell.strip() for cell in text.split(separator)]
    if cells and cells[-1] == "Comment":
        cells.pop()
    if cells and cells[0] == "X_Value" and headers.x_dimension.lower() == "time":
        cells[0] = "time (s)"
    channels = [k for k, cell in enumerate(cells) if cell not in ("X_Value", "time (s)")]
    if len(channels) == 1 and _UNTITLED.fullmatch(cells[channels[0]]):
        cells[channels[0]] = "value"  # LabVIEW's default name says nothing: the one channel
    return separator.join(cells)


_UNTITLED = re.compile(r"Untitled(?: \d+)?")
