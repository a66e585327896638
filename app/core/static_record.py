"""A real static record made ready for an Allan analysis: read in bounded memory, its gaps,
spikes and warm-up found and dealt with, and every step said (lab-reference §6: IEEE
practice trims the warm-up and records the temperature).

Reading: CSV text (``value`` per line, ``time_s,value``, ``time_s,value,temperature_c``, the
bridge's long layout ``position,angle_deg,time_s,value[,temperature_c]``, with or without a
header; commas, tabs, semicolons with decimal commas, or spaces between the columns;
``#`` and ``%`` comment lines), parsed in blocks of lines, so a 10⁷-sample record never
exists as one string.

Preparation, in this order:

* gaps (the bridge's times skip readings, k·T steps with k ≥ 2 for the median step T):
  the longest stretch without a gap is analysed -- joining across a gap would fake a
  correlation;
* spikes: readings more than ``SPIKE_LIMIT`` robust σ (1.4826·MAD of the residual from a
  9-point running median, at least one reading step) from their running median are
  replaced by it and counted;
* warm-up: from the case temperature where there is one (the stretch before it settles to
  within 10 % of its total change of its final value), else from the rate itself (64 block
  means; the first ones step monotonically towards the settled level of the second half,
  the first more than ``WARM_UP_LIMIT`` times the block-to-block scatter away): trimmed,
  at most half the record.
"""

from __future__ import annotations

import codecs
import csv
import io
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

import numpy as np

from app.core.exceptions import UserError

BLOCK_LINES = 200_000
MAX_SAMPLES = 20_000_000
SPIKE_LIMIT = 10.0
WARM_UP_LIMIT = 6.0
WARM_UP_BLOCKS = 64
MAX_TRIM_SHARE = 0.5
VALUE_NAMES = ("value", "rate", "rate_deg_h", "omega", "reading")
TIME_NAMES = ("time_s", "time", "t", "t_s", "timestamp", "timestamp_s")
TEMPERATURE_NAMES = ("temperature_c", "temperature", "temp_c", "temp")

Progress = Callable[[str, dict], None]


@dataclass
class StaticRecord:
    """A static record: rates, and where the source had them, times (s) and case
    temperatures (°C)."""

    values: np.ndarray
    times_s: np.ndarray | None = None
    temperatures_c: np.ndarray | None = None


@dataclass
class PreparedRecord:
    values: np.ndarray
    rate_hz: float
    notes: list[dict] = field(default_factory=list)  # {"key", "params", "en"}


def _note(key: str, english: str, **params) -> dict:
    return {"key": key, "params": params, "en": english}


def _chosen(column: str, names: list[str]) -> int:
    """The column asked for: its name in the header, or its number counted from 1."""
    wanted = column.strip().lower()
    if wanted in names:
        return names.index(wanted)
    if wanted.isdigit() and 1 <= int(wanted) <= len(names):
        return int(wanted) - 1
    raise UserError(
        "allan.no_such_column",
        f"The record has no column {column!r}; its columns are: {', '.join(names)}.",
        column=column,
        columns=", ".join(names),
    )


def _columns(
    header: list[str], column: str | None = None
) -> tuple[int, int | None, int | None, int | None]:
    names = [h.strip().lower() for h in header]

    def find(options):
        return next((names.index(o) for o in options if o in names), None)

    if column is not None:  # one axis of a multi-axis record, say
        return _chosen(column, names), find(TIME_NAMES), find(TEMPERATURE_NAMES), None

    wide = [n for n in names if n.startswith("position_")]
    if len(wide) > 1:  # the wide layout: one column per position
        raise UserError(
            "allan.one_position",
            f"An Allan analysis needs one static record (one position), not {len(wide)}.",
            count=len(wide),
        )
    value = find((*VALUE_NAMES, *wide))
    if value is None:
        if len(names) in (1, 2, 3):  # unknown names: the columns as without a header
            return {1: (0, None, None, None), 2: (1, 0, None, None)}.get(
                len(names), (1, 0, 2, None)
            )
        raise UserError(
            "allan.no_value_column",
            "The record has a header but no 'value' column; its columns are: "
            f"{', '.join(names)} (choose one).",
            columns=", ".join(names),
        )
    return value, find(TIME_NAMES), find(TEMPERATURE_NAMES), find(("position",))


def _is_header(cells: list[str]) -> bool:
    try:
        [float(c) for c in cells if c.strip()]
    except ValueError:
        return True
    return False


def read_static_record(
    lines: Iterable[str], *, progress: Progress | None = None, column: str | None = None
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

    Returns
    -------
    StaticRecord
        Rates in the record's unit, with times and temperatures where given.

    Raises
    ------
    UserError
        No readings, a bad cell (its line number), more than one position, or more than
        ``MAX_SAMPLES`` readings.
    """
    values, times, temps = [], [], []
    layout: tuple[int, int | None, int | None, int | None] | None = None
    position_seen: str | None = None
    block: list[list[str]] = []
    first_line = 0
    line_number = 0
    count = 0

    def flush() -> None:
        nonlocal block, first_line, count, position_seen
        if not block:
            return
        value_col, time_col, temp_col, position_col = layout
        try:
            rows = np.array(block, dtype=object)
            if position_col is not None:
                positions = set(rows[:, position_col].tolist())
                if position_seen is not None:
                    positions.add(position_seen)
                if len(positions) > 1:
                    raise UserError(
                        "allan.one_position",
                        "An Allan analysis needs one static record (one position), not "
                        f"{len(positions)}.",
                        count=len(positions),
                    )
                position_seen = next(iter(positions))
            values.append(np.asarray(rows[:, value_col], dtype=float))
            if time_col is not None:
                times.append(np.asarray(rows[:, time_col], dtype=float))
            if temp_col is not None:
                temps.append(np.asarray(rows[:, temp_col], dtype=float))
        except (ValueError, IndexError):
            bad = _first_bad_line(block, layout)
            raise UserError(
                "allan.bad_line",
                f"Line {first_line + bad} of the record is not a reading.",
                line=first_line + bad,
            ) from None
        count += len(block)
        if count > MAX_SAMPLES:
            raise UserError(
                "allan.too_many",
                f"The record has more than {MAX_SAMPLES:,} readings.",
                maximum=MAX_SAMPLES,
            )
        block = []
        if progress:
            progress("read", {"samples": count})

    width = None
    split = None
    for raw in lines:
        line_number += 1
        text = raw.strip().lstrip("\ufeff")
        if not text or text.startswith(("#", "%")):
            continue
        if split is None:
            split = _splitter(text)
        cells = split(text)
        if layout is None:
            if _is_header(cells):
                layout = _columns(cells, column)
                width = len(cells)
                continue
            width = len(cells)
            layout = {1: (0, None, None, None), 2: (1, 0, None, None)}.get(width, (1, 0, 2, None))
            if column is not None:
                numbers = [str(k) for k in range(1, width + 1)]
                layout = (_chosen(column, numbers), None, None, None)
        if len(cells) != width:
            raise UserError(
                "allan.bad_line",
                f"Line {line_number} of the record is not a reading.",
                line=line_number,
            )
        if not block:
            first_line = line_number
        block.append(cells)
        if len(block) >= BLOCK_LINES:
            flush()
    if layout is not None:
        flush()
    if not values:
        raise UserError("allan.empty", "The record holds no readings.")
    data = np.concatenate(values)
    record = StaticRecord(
        data,
        np.concatenate(times) if times else None,
        np.concatenate(temps) if temps else None,
    )
    if not np.all(np.isfinite(record.values)):
        raise UserError("readings.not_finite", "A reading is not a finite number.")
    return record


def _splitter(first: str) -> Callable[[str], list[str]]:
    """How the record's lines split into cells, decided by its first line: commas (quotes
    allowed), tabs, semicolons with decimal commas (a European spreadsheet), or runs of
    spaces (the plain text files of instruments and public data sets)."""
    if "\t" in first:
        return lambda text: [c.strip() for c in text.split("\t")]
    if ";" in first:
        return lambda text: [c.strip().replace(",", ".") for c in text.split(";")]
    if "," in first:

        def commas(text: str) -> list[str]:
            if '"' in text:
                return [c.strip() for c in next(csv.reader([text]))]
            return [c.strip() for c in text.split(",")]

        return commas
    return lambda text: text.split()


def _first_bad_line(block, layout) -> int:
    for index, row in enumerate(block):
        try:
            for col in layout[:3]:
                if col is not None:
                    float(row[col])
        except (ValueError, IndexError):
            return index
    return 0


def text_lines(data, chunk: int = 1 << 20) -> Iterable[str]:
    """Lines of UTF-8 bytes or a binary file (a BOM, CRLF or CR line ends allowed), decoded
    incrementally.

    Parameters
    ----------
    data : bytes or binary file
        The text's bytes, or a file opened in binary mode.
    chunk : int
        Bytes read at a time.

    Returns
    -------
    iterator of str
        The lines, without their line ends.
    """
    decoder = codecs.getincrementaldecoder("utf-8")()
    buffer = io.BytesIO(data) if isinstance(data, bytes | bytearray) else data
    pending = ""
    while True:
        piece = buffer.read(chunk)
        if not piece:
            break
        try:
            pending += decoder.decode(piece)
        except UnicodeDecodeError:
            raise UserError(
                "csv.encoding",
                "The file is not text (UTF-8 or GB18030): save it as CSV and try again.",
            ) from None
        parts = pending.replace("\r\n", "\n").replace("\r", "\n").split("\n")
        pending = parts.pop()
        yield from parts
    if pending:
        yield pending


def _longest_stretch(times: np.ndarray) -> tuple[slice, int, int, float]:
    steps = np.diff(times)
    interval = float(np.median(steps)) if steps.size else 0.0
    if not (interval > 0 and math.isfinite(interval)):
        raise UserError(
            "allan.bad_times", "The record's times do not increase; check the time column."
        )
    breaks = np.flatnonzero(steps >= 1.5 * interval)
    if np.any(steps <= 0):
        raise UserError(
            "allan.bad_times", "The record's times do not increase; check the time column."
        )
    edges = np.concatenate([[0], breaks + 1, [times.size]])
    lengths = np.diff(edges)
    longest = int(np.argmax(lengths))
    missing = int(np.sum(np.rint(steps[breaks] / interval) - 1))
    return slice(int(edges[longest]), int(edges[longest + 1])), int(breaks.size), missing, interval


def _despike(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    from scipy.ndimage import median_filter

    smooth = median_filter(values, size=9, mode="nearest")
    residual = values - smooth
    scale = 1.4826 * float(np.median(np.abs(residual)))
    distinct = np.unique(values[: min(values.size, 100_000)])
    step = float(np.min(np.diff(distinct))) if distinct.size > 1 else 0.0
    scale = max(scale, step)
    if scale <= 0:
        return values, np.zeros(0, dtype=int)
    spikes = np.flatnonzero(np.abs(residual) > SPIKE_LIMIT * scale)
    if spikes.size:
        values = values.copy()
        values[spikes] = smooth[spikes]
    return values, spikes


def _warm_up_end(values: np.ndarray, temperatures: np.ndarray | None) -> tuple[int, str, float]:
    """Index where the warm-up ends (0: none), how it was seen, and its size (°/h or °C)."""
    limit = int(values.size * MAX_TRIM_SHARE)
    if temperatures is not None and temperatures.size == values.size:
        final = float(np.median(temperatures[-max(1, temperatures.size // 10) :]))
        change = float(np.max(temperatures) - np.min(temperatures))
        if change > 1.0:
            unsettled = np.flatnonzero(np.abs(temperatures - final) > 0.1 * change)
            end = int(unsettled[-1]) + 1 if unsettled.size else 0
            if end:
                return min(end, limit), "temperature", change
    size = values.size // WARM_UP_BLOCKS
    if size < 4:
        return 0, "", 0.0
    means = values[: size * WARM_UP_BLOCKS].reshape(WARM_UP_BLOCKS, size).mean(axis=1)
    settled = means[WARM_UP_BLOCKS // 2 :]
    level = float(np.median(settled))
    scatter = 1.4826 * float(np.median(np.abs(np.diff(settled)))) / math.sqrt(2.0)
    if scatter <= 0:
        return 0, "", 0.0
    deviation = means - level
    if abs(deviation[0]) < WARM_UP_LIMIT * scatter:
        return 0, "", 0.0
    sign = np.sign(deviation[0])
    head = deviation[:4] * sign
    if not np.all(np.diff(head) < 0):  # a warm-up moves steadily towards the settled level
        return 0, "", 0.0
    inside = np.flatnonzero(np.abs(deviation) < 2.0 * scatter)
    end_block = int(inside[0]) if inside.size else WARM_UP_BLOCKS // 2
    return min(end_block * size, limit), "rate", float(deviation[0])


def prepare_record(
    record: StaticRecord, rate_hz: float | None, *, max_tau_s: float | None = None
) -> PreparedRecord:
    """Gaps, spikes and warm-up dealt with; the rate from the times where none is given.

    Parameters
    ----------
    record : StaticRecord
        The record as read (rates in °/h).
    rate_hz : float or None
        The sample rate (Hz); None takes it from the times' median step.
    max_tau_s : float, optional
        The longest τ (s) asked for: refused when the record (after trimming) is shorter
        than 2·τ, a note when shorter than 10·τ.

    Returns
    -------
    PreparedRecord
        The rates to analyse, the rate, and notes of what was done.

    Raises
    ------
    UserError
        No rate and no times, times that do not increase, or a record too short.

    References
    ----------
    IEEE Std 952-1997, annex C (test procedure: warm-up, temperature); lab-reference §6.
    """
    values = np.asarray(record.values, dtype=float)
    temperatures = record.temperatures_c
    notes: list[dict] = []
    if record.times_s is not None and record.times_s.size > 2:
        stretch, gaps, missing, interval = _longest_stretch(np.asarray(record.times_s, float))
        if rate_hz is None:
            rate_hz = 1.0 / interval
        if gaps:
            kept = stretch.stop - stretch.start
            notes.append(
                _note(
                    "allan.note_gaps",
                    f"Gaps in the record: {gaps} ({missing} readings missing). The longest "
                    f"stretch without one, {kept} readings ({kept / rate_hz:.0f} s), was analysed.",
                    gaps=gaps,
                    missing=missing,
                    kept=kept,
                    seconds=round(kept / rate_hz),
                )
            )
            values = values[stretch]
            temperatures = None if temperatures is None else temperatures[stretch]
    if rate_hz is None:
        raise UserError("allan.no_rate", "Give the sample rate (the record has no time column).")
    if not (rate_hz > 0 and math.isfinite(rate_hz)):
        raise UserError("allan.bad_rate", "The sample rate must be a positive number.")
    if values.size >= 32:
        values, spikes = _despike(values)
        if spikes.size:
            notes.append(
                _note(
                    "allan.note_spikes",
                    f"Spikes more than {SPIKE_LIMIT:.0f} σ from their neighbours: {spikes.size}, "
                    f"replaced by the local median (the first at {spikes[0] / rate_hz:.1f} s).",
                    n=int(spikes.size),
                    first_s=round(spikes[0] / rate_hz, 1),
                )
            )
        end, seen_by, size = _warm_up_end(values, temperatures)
        if end:
            english = (
                f"The first {end / rate_hz:.0f} s were trimmed: the gyro was still warming up "
                + (
                    f"(its case temperature changed by {size:.1f} °C)."
                    if seen_by == "temperature"
                    else f"(its rate moved by {abs(size):.3g} °/h towards its settled value)."
                )
            )
            notes.append(
                _note(
                    f"allan.note_trimmed_{seen_by}",
                    english,
                    seconds=round(end / rate_hz),
                    change=f"{abs(size):.3g}",
                )
            )
            values = values[end:]
    record_s = values.size / rate_hz
    if max_tau_s is not None:
        if record_s < 2.0 * max_tau_s:
            raise UserError(
                "allan.too_short_for_tau",
                f"The record covers {record_s:.0f} s; a τ of {max_tau_s:g} s needs at least "
                f"{2 * max_tau_s:.0f} s (better ten times τ).",
                seconds=round(record_s),
                tau=max_tau_s,
                minimum=round(2 * max_tau_s),
            )
        if record_s < 10.0 * max_tau_s:
            notes.append(
                _note(
                    "allan.note_few_stretches",
                    f"The record covers only {record_s / max_tau_s:.1f} τ of {max_tau_s:g} s: "
                    "the longest τ's rest on few independent stretches.",
                    ratio=f"{record_s / max_tau_s:.1f}",
                    tau=max_tau_s,
                )
            )
    return PreparedRecord(values, float(rate_hz), notes)
