"""The class dashboard's numeric cells, formatted once per row in Python.

A class of 300 is 300 rows of a dozen numbers, each shown and kept as a sort key; written
as expressions in the template they were about half of the page's rendering (a call or an
attribute lookup through Jinja for every one: ≈ 100 µs a row; bench/README.md, issue 32).
The page shows exactly what the template's expressions showed."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from app.review.service import StudentRow

EMPTY = "—"


@dataclass(frozen=True, slots=True)
class Cell:
    """What a cell shows, and its sort key (``data-value``; empty when there is none)."""

    text: str = EMPTY
    value: str = ""


@dataclass(frozen=True, slots=True)
class RowCells:
    submitted: Cell
    heading: Cell
    heading_error: Cell
    latitude: Cell
    latitude_error: Cell
    earth_rate: Cell
    earth_rate_error: Cell


def _number(value, pattern: str, key=lambda v: v) -> Cell:
    return Cell() if value is None else Cell(pattern % value, str(key(value)))


def row_cells(row: StudentRow, when: Callable) -> RowCells:
    """The row's submitted time (``when``: the page's time formatter, zone named in the
    column's heading), its results and their errors against the student's truth."""
    heading = row.results.get("heading") or {}
    latitude = row.results.get("latitude") or {}
    submitted = row.submitted_at
    return RowCells(
        submitted=Cell(when(submitted, "MMMd", zone=False), submitted.isoformat())
        if submitted
        else Cell(),
        heading=_number(heading.get("azimuth_deg"), "%.2f°"),
        heading_error=_number(row.check_error("heading"), "%+.2f°", abs),
        latitude=_number(latitude.get("latitude_deg"), "%.2f°"),
        latitude_error=_number(row.check_error("latitude"), "%.2f %%"),
        earth_rate=_number(latitude.get("earth_rate_deg_h"), "%.3f"),
        earth_rate_error=_number(row.check_error("earth_rate"), "%.2f %%"),
    )


def class_cells(rows: list[StudentRow], when: Callable) -> dict[int, RowCells]:
    """Each student's (by id) row cells."""
    return {row.student.id: row_cells(row, when) for row in rows}
