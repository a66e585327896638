"""The long readings layout: one reading per row beside its position, read from a file's
rows and written as GyroLab exports it (``position,angle_deg,time_s,value`` with an
optional ``temperature_c``).  Which columns a header names is
:func:`app.core.long_headers.long_columns`'s to say; the positions are keyed by their
number ("3", "P3", "位置3"; kept, so a file of position 3 alone is position 3), a label, or
the turntable's angle, whose unit may be written ("90°", "90度")."""

from __future__ import annotations

import io

import numpy as np

from app.core.clock_stamps import clock_seconds, is_clock_stamp, spread_within_ticks
from app.core.exceptions import UserError
from app.core.readings_data import MAX_POSITION_NUMBER, WIDE_COLUMN, Readings, cell_number
from app.core.table_headers import ANGLE, column_name, evenly_round
from app.core.typed_numbers import is_number


def parse_long(index: dict[str, int], rows) -> Readings:
    """Read the rows of a long table: one reading per row, keyed by its position (a number,
    "P2", "位置2", a label) or by the turntable's angle.

    Parameters
    ----------
    index : dict of str to int
        The column of each field the header names (``position`` or ``angle_deg``, and
        ``value``; ``time_s`` and ``temperature_c`` where given), from
        :func:`app.core.long_headers.long_columns`.
    rows : list of (int, list of str)
        The rows under the header, each with its line in the file.

    Returns
    -------
    Readings
        The positions in the file's order of first appearance, or by their numbers where
        every label is one (kept as the file gives them, counted from 1 where the file
        counts from 0); angles where the table gives them, or where its positions are
        named by angles (0, 90, 180, 270); times and temperatures where it has them.

    Raises
    ------
    UserError
        A row without its position, a reading that is no number, an angle that changes
        within a position or returns to one left, a position named twice.
    """
    keyed = "position" if "position" in index else "angle_deg"
    clock = next((name for name in ("time_s", "time_ms") if name in index), None)
    origin: list[int] = []  # the first date of clock stamps, shared by the whole file
    labels: list[str] = []
    grouped: dict[str, dict] = {}
    for line, row in rows:

        def cell(name: str, row=row) -> str:
            position = index.get(name)
            return row[position].strip() if position is not None and position < len(row) else ""

        label = cell(keyed)
        if not label:
            raise UserError("csv.no_position", line=line)
        if keyed == "angle_deg":
            label = _angle_label(_angle(label, line))
        entry = grouped.get(label)
        if entry is None:
            entry = grouped[label] = {
                "values": [], "times": [], "temps": [], "angle": None, "lines": []
            }  # fmt: skip
            labels.append(label)
        elif keyed == "angle_deg" and labels[-1] != label:
            raise UserError("csv.angle_returns", line=line, angle=label)
        entry["values"].append(cell_number(cell("value"), line, "value"))
        entry["lines"].append(line)
        if clock is not None:
            entry["times"].append(_seconds(cell(clock), line, clock, origin))
        if "temperature_c" in index:
            entry["temps"].append(cell_number(cell("temperature_c"), line, "temperature_c"))
        if "angle_deg" in index:
            angle = _angle(cell("angle_deg"), line)
            if entry["angle"] is None:
                entry["angle"] = angle
            elif abs(entry["angle"] - angle) > 1e-9:
                raise UserError(
                    "csv.angle_changes",
                    line=line,
                    position=label,
                )
    if not labels:
        raise UserError("csv.empty")
    numbers = _position_numbers(labels) if keyed == "position" else None
    has_angles = "angle_deg" in index
    if numbers is not None and not has_angles and _angles_named_positions(numbers):
        for label, angle in zip(labels, numbers, strict=True):  # "position" 0, 90, 180, 270
            grouped[label]["angle"] = float(angle)
        has_angles = True
        numbers = None
    if numbers is not None:
        order = sorted(range(len(labels)), key=numbers.__getitem__)
        labels, numbers = [labels[k] for k in order], [numbers[k] for k in order]
    angles = [grouped[label]["angle"] for label in labels] if has_angles else None
    time_notes: list[tuple[str, dict]] = []
    times = None
    if clock:
        times, time_notes = _rising_times([grouped[label] for label in labels], labels)
    positions = [np.array(grouped[label]["values"]) for label in labels]
    temperatures = None
    if "temperature_c" in index:
        temperatures = [np.array(grouped[label]["temps"]) for label in labels]
    return Readings(
        positions, angles, times, "long", temperatures, numbers=numbers, time_notes=time_notes
    )


def _rising_times(
    entries: list[dict], labels: list[str]
) -> tuple[list[np.ndarray] | None, list[tuple[str, dict]]]:
    """Each position's times, rising: a time that goes back within a position is refused
    (its line); a clock coarser than the readings (several share a stamp) is spread over
    each tick (:func:`app.core.clock_stamps.spread_within_ticks`); one stamp for a whole
    position is no reading's time, and the column is passed over.  With what is said."""
    times = [np.array(entry["times"]) for entry in entries]
    notes: list[tuple[str, dict]] = []
    for label, entry, stamps in zip(labels, entries, times, strict=True):
        steps = np.diff(stamps)
        if steps.size and bool(np.any(steps < 0)):
            at = int(np.argmax(steps < 0)) + 1
            raise UserError(
                "csv.time_goes_back",
                line=entry["lines"][at],
                position=label,
                time=f"{stamps[at]:.6g}",
                before=f"{stamps[at - 1]:.6g}",
            )
    if any(stamps.size > 1 and np.unique(stamps).size == 1 for stamps in times):
        return None, [("csv.times_dropped", {})]
    if any(bool(np.any(np.diff(stamps) == 0)) for stamps in times):
        times = [spread_within_ticks(s) if np.any(np.diff(s) == 0) else s for s in times]
        notes.append(("csv.times_spread", {}))
    return times, notes


def _seconds(cell: str, line: int, clock: str, origin: list[int]) -> float:
    """A time as a cell gives it, in seconds: a number of seconds (``time_s``) or of
    milliseconds (``time_ms``), or a logger's clock stamp ("12:00:01.5", "2026-11-28
    12:00:01"; :func:`app.core.clock_stamps.clock_seconds`, from ``origin``'s midnight)."""
    if not is_number(cell) and is_clock_stamp(cell):  # a number is never asked a clock's forms
        try:
            return float(clock_seconds([cell], origin)[0])
        except ValueError:
            pass  # "25:00:00": said as not a number below
    seconds = cell_number(cell, line, clock)
    return seconds / 1000.0 if clock == "time_ms" else seconds


def _angle_label(angle: float) -> str:
    return f"{angle:g}"


def _angle(cell: str, line: int) -> float:
    """A turntable angle as a cell gives it: "90", or with its unit, "90°", "90度"."""
    written = ANGLE.fullmatch(cell)
    return cell_number(written.group(1) if written else cell, line, "angle_deg")


def _position_numbers(labels: list[str]) -> list[int] | None:
    """The positions' numbers as the labels give them ("3", "P3", "位置3", "第3位置"),
    counted from 1 where the labels count from 0; None where a label is no number."""
    numbers = []
    for label in labels:
        name = column_name(label)
        match = WIDE_COLUMN.match(name)
        if match:
            numbers.append(int(match.group(1)))
        elif label.isdigit():
            numbers.append(int(label))
        else:
            return None
    if max(numbers) > MAX_POSITION_NUMBER:
        raise UserError("csv.position_number", position=max(numbers), limit=MAX_POSITION_NUMBER)
    if len(set(numbers)) != len(numbers):
        raise UserError("csv.position_twice_named", positions=", ".join(labels))
    if 0 in numbers and sorted(numbers) == list(range(len(numbers))):
        return [number + 1 for number in numbers]  # counted from 0
    return numbers


def _angles_named_positions(numbers: list[int]) -> bool:
    """Labels that are the turntable's angles, not positions' numbers: 0, 90, 180, 270."""
    return max(numbers) > 8 and evenly_round([float(n) for n in numbers], from_zero=False)


def readings_to_long_csv(
    positions, angles_deg, times_s=None, value_format: str = ".6f", temperatures_c=None
) -> str:
    """Write the long layout: ``position,angle_deg,time_s,value[,temperature_c]``.

    Parameters
    ----------
    positions : sequence of numpy.ndarray
        Each position's readings (°/h).
    angles_deg : sequence of float
        Each position's angle (°).
    times_s : sequence of numpy.ndarray, optional
        Each reading's time (s); default 0, 1, 2 ... within each position.
    value_format : str
        Format of the readings.
    temperatures_c : sequence of numpy.ndarray, optional
        Each reading's case temperature (°C).

    Returns
    -------
    str
        The CSV text.
    """
    buffer = io.StringIO()
    buffer.write("position,angle_deg,time_s,value" + (",temperature_c" if temperatures_c else ""))
    buffer.write("\n")
    for number, (values, angle) in enumerate(zip(positions, angles_deg, strict=True), start=1):
        times = times_s[number - 1] if times_s is not None else np.arange(len(values), dtype=float)
        temps = temperatures_c[number - 1] if temperatures_c else None
        for index, (time, value) in enumerate(zip(times, values, strict=True)):
            extra = f",{temps[index]:.3f}" if temps is not None else ""
            buffer.write(f"{number},{angle:.6g},{time:.3f},{value:{value_format}}{extra}\n")
    return buffer.getvalue()
