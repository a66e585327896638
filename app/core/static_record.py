"""A real static record for an Allan analysis, read in bounded memory.

Reading: CSV text (``value`` per line, ``time_s,value``, ``time_s,value,temperature_c``, the
bridge's long layout ``position,angle_deg,time_s,value[,temperature_c]``, with or without a
header; commas, tabs or semicolons (then decimal commas), or spaces between the columns
(Excel's first line "sep=;" naming the separator);
one column with decimal commas ("0,0123" per line) where it cannot be times and values;
a row of units under the header passed over; a time column in seconds, in milliseconds
(``time_ms``) or as a logger's clock -- "2026-11-28 10:00:00.123", ISO 8601, a time of day
carried past midnight -- read as seconds from the first reading; without a header, a
rising first column read as the times where the rates' column is chosen, and a rate beside
a status flag read without times; a spreadsheet's empty last column dropped; a last line
with fewer cells than the readings (cut off when the logger stopped, or a closing remark)
left out, with a note; ``#``, ``%`` and ``//`` comment lines, the last one before the
readings read as the header where it names their columns -- EuRoC, Kalibr and ROS write
it so (:mod:`app.core.record_preamble`); which column is which:
:mod:`app.core.record_columns`; what a name says of units: :mod:`app.core.column_names`;
how its lines split: :mod:`app.core.record_lines`), parsed in blocks of lines
(:mod:`app.core.record_blocks`), so a 10⁷-sample record never exists as one string.  Whether
a file can only be a record, never a table of positions: :mod:`app.core.record_kinds`.

Preparing the record for the analysis: :mod:`app.core.record_preparation`.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

from app.core.clock_stamps import TimeColumn, seconds_from_first
from app.core.column_names import AngleOutput, comment_text
from app.core.exceptions import UserError
from app.core.labview_lvm import LabviewHeaders, is_labview_measurement, labview_lines
from app.core.monitor_stamps import is_stamped_capture, unstamped_lines
from app.core.record_blocks import Progress, RecordBlocks
from app.core.record_columns import Layout
from app.core.record_lines import (
    LOOK_AHEAD_LINES,
    joined_decimal_comma,
    line_splitter,
    one_column_with_decimal_commas,
)
from app.core.record_preamble import Preamble, describes_the_record, stated_rate_hz
from app.core.sentence_records import Sentences, is_sentence_record, sentence_lines
from app.core.spreadsheet_text import separator_hint

# notes on lines of the file that were not read, which every reader of a record says
LEFT_OUT = frozenset(
    {
        "allan.note_last_line_left_out",
        "allan.note_about_the_record",
        "allan.note_about_it",
        "allan.note_labview",
        "allan.note_labview_segments",
        "allan.note_sentences",
        "allan.note_sentences_checksum",
        "allan.note_sentences_other",
        "allan.note_monitor_stamps",
    }
)


@dataclass
class StaticRecord:
    """A static record: rates, and where the source had them, times (s) and case
    temperatures (°C); the rates' unit where the header names it, and notes on how the
    record was read (``{"key", "params"}``, words in the catalogues)."""

    values: np.ndarray
    times_s: np.ndarray | None = None
    temperatures_c: np.ndarray | None = None
    unit: str | None = None
    notes: list[dict] = field(default_factory=list)
    angle: AngleOutput | None = None  # the readings are angles per output, not rates
    stated_rate_hz: float | None = None  # "Sample rate: 2 Hz" in the lines above the table
    # the note that says the stated rate was used, where the file states it otherwise than
    # above a table (a MATLAB file's Fs); None: ``allan.note_rate_stated``
    rate_note: dict | None = None


def read_static_record(
    lines: Iterable[str],
    *,
    progress: Progress | None = None,
    column: str | None = None,
    guess: bool = True,
    finite: bool = True,
) -> StaticRecord:
    """Parse a static record from an iterable of text lines, block by block.

    Parameters
    ----------
    lines : iterable of str
        The CSV's lines (a text file, or ``io.StringIO``).
    progress : callable, optional
        Called as ``progress("read", {"samples": n})`` after every block.
    column : str, optional
        The column of the rates: a header name or a number from 1 (e.g. one axis of an
        IMU's record); by default ``value`` (or the layouts above).
    guess : bool
        Read a header of one to three unknown names as the columns without a header
        (False: such a header is refused).
    finite : bool
        Refuse a reading that is not a finite number (a lab position's record); False
        keeps them as NaN or ±inf, a logger's lost readings, for
        :func:`app.core.record_preparation.prepare_record` to mend or cut out.

    Returns
    -------
    StaticRecord
        Rates in the record's unit, with times and temperatures where given.

    Raises
    ------
    UserError
        No readings, a bad cell (its line number), more than one position, or more than
        :data:`app.core.record_blocks.MAX_SAMPLES` readings.
    """
    time_guessed = False  # a bare record's first column taken as its times
    layout: Layout | None = None
    blocks: RecordBlocks | None = None  # the rows converted, once the layout is known
    notes: list[dict] = []
    line_number = 0

    width = None
    preamble = Preamble()
    short: tuple[int, str] | None = None  # a line with fewer cells than the readings
    about: list[tuple[int, str]] = []  # lines about the record above its table
    lines = iter(lines)
    first = list(itertools.islice(lines, LOOK_AHEAD_LINES))
    if is_stamped_capture(first):  # "10:00:00.123 -> 10.74": the stamp a time column
        lines = unstamped_lines(itertools.chain(first, lines))
        first = list(itertools.islice(lines, LOOK_AHEAD_LINES))
        notes.append({"key": "allan.note_monitor_stamps", "params": {}})
    labview = None
    if is_labview_measurement("".join(first[:50])[:200]):
        labview = LabviewHeaders()  # its headers passed over, its rate where it states one
        lines = labview_lines(itertools.chain(first, lines), labview)
        first = list(itertools.islice(lines, LOOK_AHEAD_LINES))
    sentences = None
    if labview is None and is_sentence_record(first):
        sentences = Sentences()  # "$VNYMR,…*CS" lines: their fields, named as the maker's
        lines = sentence_lines(itertools.chain(first, lines), sentences)
        first = list(itertools.islice(lines, LOOK_AHEAD_LINES))
        # the fields' names, as a header in a comment above the first reading would be
        preamble.comment, preamble.comment_line = sentences.header, 0
    split = joined_decimal_comma if one_column_with_decimal_commas(first) else None
    for raw in itertools.chain(first, lines):
        line_number += 1
        text = raw.strip().lstrip("\ufeff")
        if not text:
            continue
        if (remark := comment_text(text)) is not None:
            if layout is None:
                preamble.comment, preamble.comment_line = remark, line_number
            continue
        if layout is None and preamble.header is None and describes_the_record(text):
            about.append((line_number, text))  # "Device: DSP-1750" above the table
            continue
        if split is None:
            if (hint := separator_hint(raw.rstrip("\r\n"))) is not None:  # Excel's "sep=;"
                split = line_splitter(hint)
                continue
            split = line_splitter(text)
        cells = split(text)
        if preamble.takes_units(cells):
            continue  # "s, °/h, °C" under the names
        if layout is None:
            if preamble.takes_header(cells, text, split):
                continue
            width = len(cells)
            layout, time_guessed, said = preamble.layout(
                cells, line_number, first, split, column, guess
            )
            notes += said
            blocks = RecordBlocks(layout, TimeColumn(layout.time_scale), progress)
        if short is not None:  # a reading after a short line: that line was a bad one
            raise UserError("allan.bad_line", line=short[0])
        if len(cells) != width:
            if len(cells) < width and blocks.held:  # the last line, if none follows
                short = (line_number, text)
                continue
            raise UserError(
                "allan.bad_line",
                line=line_number,
            )
        blocks.add(line_number, cells)
    if about:
        first, last = about[0][0], about[-1][0]
        notes.append(
            {
                "key": "allan.note_about_the_record" if last > first else "allan.note_about_it",
                "params": {"first": first, "last": last, "text": _shortened(about[0][1])},
            }
        )
    if labview is not None:
        params = {"first": labview.first_line, "last": labview.last_line}
        if labview.segments > 1:
            notes.append({"key": "allan.note_labview_segments", "params": {
                **params, "segments": labview.segments}})  # fmt: skip
        else:
            notes.append({"key": "allan.note_labview", "params": params})
    if sentences is not None and sentences.kept:
        # the names are the maker's, not a comment line's: said as such
        notes = [note for note in notes if note["key"] != "allan.note_comment_header"]
        notes += sentences.notes()
    if short is not None:  # cut off when the logger stopped, or a closing remark
        notes.append(
            {
                "key": "allan.note_last_line_left_out",
                "params": {"line": short[0], "text": _shortened(short[1])},
            }
        )
    if blocks is not None:
        blocks.flush()
    if blocks is None or not blocks.values:
        raise UserError("allan.empty")
    all_times = np.concatenate(blocks.times) if blocks.times else None
    if time_guessed:
        if np.all(np.diff(all_times) >= 0):
            notes.append({"key": "allan.note_first_column_times", "params": {}})
        elif blocks.clock.clock:  # a clock's stamps that go back are no counter's wrap
            raise UserError("allan.bad_times")
        else:  # it rose only at first: a counter that wraps, say -- no times
            all_times = None
    clock = blocks.clock
    if clock.inferred:
        notes.append(
            {
                "key": "allan.note_spreadsheet_days"
                if clock.inferred == "days"
                else "allan.note_time_unit",
                "params": {"unit": clock.inferred, "column": layout.time + 1},
            }
        )
    record = StaticRecord(
        np.concatenate(blocks.values),
        seconds_from_first(all_times) if clock.clock else all_times,
        np.concatenate(blocks.temperatures) if blocks.temperatures else None,
        layout.rate_unit,
        notes,
        layout.angle,
        next((rate for _, text in about if (rate := stated_rate_hz(text))), None)
        or (labview.rate_hz if labview is not None else None),
    )
    if finite and not np.all(np.isfinite(record.values)):
        raise UserError("readings.not_finite")
    return record


def _shortened(text: str, length: int = 40) -> str:
    """A line as a note quotes it: at most ``length`` characters."""
    return text if len(text) <= length else text[: length - 1] + "…"
