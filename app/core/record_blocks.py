"""A static record's lines of readings turned into numbers a block at a time, so that a
10⁷-line record is never held as cells all at once: the rates, the times (each row's
clock stamp or number in seconds) and the case temperatures of the columns a
:class:`app.core.record_columns.Layout` names, with the line of the first bad cell, one
position only, and a bound on the count.  The lines themselves are read by
:mod:`app.core.static_record`."""

from __future__ import annotations

import math
import re
from collections.abc import Callable

import numpy as np

from app.core.clock_stamps import TimeColumn
from app.core.exceptions import UserError
from app.core.record_columns import Layout

BLOCK_LINES = 200_000
MAX_SAMPLES = 20_000_000

Progress = Callable[[str, dict], None]


class RecordBlocks:
    """The readings of a record's rows, converted each ``BLOCK_LINES`` rows.

    Parameters
    ----------
    layout : Layout
        Which column holds the rates, the times, the temperatures and the position.
    clock : TimeColumn
        The time column's reader (its unit, or a clock's origin, shared by the blocks).
    progress : callable, optional
        Called as ``progress("read", {"samples": n})`` after every block.
    """

    def __init__(self, layout: Layout, clock: TimeColumn, progress: Progress | None) -> None:
        self.layout, self.clock, self.progress = layout, clock, progress
        self.values: list[np.ndarray] = []
        self.times: list[np.ndarray] = []
        self.temperatures: list[np.ndarray] = []
        self.count = 0  # rows converted
        self._rows: list[list[str]] = []
        self._first_line = 0  # the file's line of the block's first row
        self._position: str | None = None  # the one position a bridge's record holds

    def add(self, line: int, cells: list[str]) -> None:
        """One row of readings, at the file's ``line``; the block is converted when full."""
        if not self._rows:
            self._first_line = line
        self._rows.append(cells)
        if len(self._rows) >= BLOCK_LINES:
            self.flush()

    @property
    def held(self) -> bool:
        """Whether any row has been added (converted or not)."""
        return bool(self.count or self._rows)

    def flush(self) -> None:
        """Convert the rows held: a bad cell is refused with its line (``allan.bad_line``),
        a second position (``allan.one_position``) and more than ``MAX_SAMPLES`` rows
        (``allan.too_many``) too."""
        if not self._rows:
            return
        layout = self.layout
        try:
            rows = np.array(self._rows, dtype=object)
            if layout.position is not None:
                positions = set(rows[:, layout.position].tolist())
                if self._position is not None:
                    positions.add(self._position)
                if len(positions) > 1:
                    raise UserError("allan.one_position", count=len(positions))
                self._position = next(iter(positions))
            self.values.append(_floats(rows[:, layout.value]))
            if layout.time is not None:
                self.times.append(self.clock.seconds(rows[:, layout.time]))
            if layout.temperature is not None:
                self.temperatures.append(_floats(rows[:, layout.temperature]))
        except UserError:
            raise  # a second position: said as such, not as a bad line
        except (ValueError, IndexError):
            bad = _first_bad_row(self._rows, layout)
            raise UserError("allan.bad_line", line=self._first_line + bad) from None
        self.count += len(self._rows)
        if self.count > MAX_SAMPLES:
            raise UserError("allan.too_many", maximum=MAX_SAMPLES)
        self._rows = []
        if self.progress:
            self.progress("read", {"samples": self.count})


# Microsoft's C runtime before 2015 printed a NaN as "1.#QNAN" or "-1.#IND", an infinity
# as "1.#INF" (and later "-nan(ind)"): a Windows logger's mark of a lost reading, as
# LabVIEW's "NaN" is
_MSVC_NOT_A_NUMBER = re.compile(r"[+-]?(?:1\.#(?:q|s)?nan|1\.#ind|nan\((?:ind|snan|qnan)\))0*")
_MSVC_INFINITY = re.compile(r"([+-]?)1\.#inf0*")


def reading(cell: str) -> float:
    """One cell's reading, a C runtime's spelling of NaN or infinity included.

    Parameters
    ----------
    cell : str
        "10.0346", "nan", "1.#QNAN", "-1.#IND", "1.#INF", "-nan(ind)" ….

    Returns
    -------
    float
        The number (NaN or ±inf for those spellings).

    Raises
    ------
    ValueError
        The cell is no number.
    """
    try:
        return float(cell)
    except ValueError:
        text = cell.strip().lower()
        if _MSVC_NOT_A_NUMBER.fullmatch(text):
            return math.nan
        infinity = _MSVC_INFINITY.fullmatch(text)
        if infinity:
            return -math.inf if infinity.group(1) == "-" else math.inf
        raise


def _floats(cells: np.ndarray) -> np.ndarray:
    try:
        return np.asarray(cells, dtype=float)
    except ValueError:  # a C runtime's NaN, say; else the bad cell is found by its line
        return np.array([reading(cell) for cell in cells], dtype=float)


def _first_bad_row(rows: list[list[str]], layout: Layout) -> int:
    for index, row in enumerate(rows):
        try:
            reading(row[layout.value])
            if layout.temperature is not None:
                reading(row[layout.temperature])
            if layout.time is not None and not TimeColumn.readable(row[layout.time]):
                return index
        except (ValueError, IndexError):
            return index
    return 0
