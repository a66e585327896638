"""The student lab's file routes: a CSV or Excel file's readings previewed (with the
positions and angles they will be saved as, and what was passed over) and saved, and a
workbook's sheet of readings, or a MATLAB or NumPy file's vectors, read as text.  Parsing
happens before the session is looked up, so no write transaction waits on it."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Body, Depends, Query, Request

from app.accounts.deps import CsrfProtected, CurrentUser
from app.core.array_text import array_file_text, is_array_file
from app.core.exceptions import UserError
from app.core.one_position_records import (
    RECORD_PROBLEMS,
    OnePositionRecord,
    parse_one_position_record,
)
from app.core.readings import parse_readings_csv
from app.core.readings_data import Readings
from app.core.record_kinds import written_as_a_record
from app.core.table_headers import angle_list, turned_other_way
from app.core.units import canonical_unit, check_named_unit, to_deg_per_hour
from app.core.workbook_text import workbook_readings
from app.lab.schemas import CsvUpload
from app.lab.service import record_positions, recordable_session
from app.lab.sim import nominal_angle, position_count
from app.lab.store import POSITIONS, check_position, current_takes
from app.models import InputMethod, LabSession, Part
from app.web.deps import ObjectId, ReadOnlySession, RowWriteSession, SessionDep
from app.web.i18n import translate
from app.web.render import request_language
from app.web.work_slots import pool

router = APIRouter(prefix="/lab", tags=["pages: lab"], include_in_schema=False)

MAX_CSV_CHARS = 5_000_000
MAX_BINARY_FILE_BYTES = 5_000_000  # as a CSV file chosen on the page (lab.js MAX_FILE_BYTES)


def parse_csv_upload(body: CsvUpload, *, suggest: bool = False) -> OnePositionRecord:
    """The file's readings, before any session is looked up (so that no write transaction
    waits on parsing); for one position's record of several axes, the columns offered and
    the one read (``suggest``: the likeliest where none is chosen, for the preview)."""
    if len(body.text) > MAX_CSV_CHARS:
        raise UserError(
            "lab.file_too_large",
            limit_mb=MAX_CSV_CHARS // 1_000_000,
        )
    unit = canonical_unit(body.unit)
    if body.column is not None or written_as_a_record(body.text):
        # a column chosen, a header behind '#' (an IMU's record) or LabVIEW's file: a record
        return checked(parse_one_position_record(body.text, unit, body.column, suggest=suggest))
    try:
        parsed = OnePositionRecord(parse_readings_csv(body.text, part=body.part))
    except UserError as error:
        if error.key != "csv.unknown_layout":
            raise
        try:  # one position's record, as a gyro's logger writes it
            parsed = parse_one_position_record(body.text, unit, body.column, suggest=suggest)
        except UserError as record_error:
            if record_error.key in RECORD_PROBLEMS:  # a record, with a problem in it
                raise
            raise error from None  # neither: the table's message, which names the layouts
    check_named_unit(parsed.readings.named_unit, unit)  # a table's "(°/s)": not read as °/h
    return checked(parsed)


def checked(parsed: OnePositionRecord) -> OnePositionRecord:
    check_position_count(len(parsed.readings.positions), POSITIONS)
    return parsed


def record_position(session: LabSession, body: CsvUpload, db) -> int:
    """The position a one-position record is for: the student's choice, else (in the
    preview) the part's first position not yet recorded."""
    if body.position is not None:
        check_position(session, body.part, body.position)
        return body.position
    done = {take.position for take in current_takes(db, session.id) if take.part == body.part}
    free = [k for k in range(1, position_count(session) + 1) if k not in done]
    return free[0] if free else 1


def check_position_count(count: int, limit: int) -> None:
    """A file's positions fit the session: 4, or 8 in the symmetric order."""
    if count > limit:
        raise UserError(
            "lab.too_many_positions",
            count=count,
            limit=limit,
        )


async def binary_file_body(request: Request) -> bytes:
    """A binary file's bytes, as the page sends them (the only async step: reading them)."""
    data = await request.body()
    if len(data) > MAX_BINARY_FILE_BYTES:
        raise UserError("lab.file_too_large", limit_mb=MAX_BINARY_FILE_BYTES // 1_000_000)
    return data


@router.post("/sessions/{session_id}/csv/binary", dependencies=[CsrfProtected, ReadOnlySession])
def binary_file_as_text(
    session_id: ObjectId,
    user: CurrentUser,
    db: SessionDep,
    data: Annotated[bytes, Depends(binary_file_body)],
    part: Annotated[Part, Query()] = Part.heading,
    sheet: Annotated[str | None, Query(min_length=1, max_length=100)] = None,
):
    """A file chosen on the page that is not text, as the text the page then previews and
    saves as a CSV file's: an Excel workbook's sheet of readings (``sheet``, else the one
    for ``part``) and the sheets that hold readings, to choose from
    (:func:`app.core.workbook_text.workbook_readings`); a MATLAB or NumPy file's vectors
    as one position's record (:func:`app.core.array_text.array_file_text`)."""
    recordable_session(db, user, session_id, InputMethod.csv)
    with pool("workbooks").slot(user.id):
        if is_array_file(data):
            text, sheet, sheets = array_file_text(data), None, ()
        else:
            book = workbook_readings(data, sheet, part.value)
            text, sheet, sheets = book.text, book.sheet, book.sheets
    if len(text) > MAX_CSV_CHARS:
        raise UserError("lab.file_too_large", limit_mb=MAX_CSV_CHARS // 1_000_000)
    return {"text": text, "sheet": sheet, "sheets": list(sheets)}


@router.post("/sessions/{session_id}/csv/preview", dependencies=[CsrfProtected, ReadOnlySession])
def preview_csv(
    session_id: ObjectId,
    user: CurrentUser,
    db: SessionDep,
    body: Annotated[CsvUpload, Body()],
    request: Request,
):
    session = recordable_session(db, user, session_id, InputMethod.csv)
    parsed = parse_csv_upload(body, suggest=True)
    readings = parsed.readings
    check_position_count(len(readings.positions), position_count(session))
    single = readings.layout == "record"
    first = record_position(session, body, db) if single else 1
    numbers = file_positions(session, body.part, readings, first)
    rows = []
    for slot, (index, values) in enumerate(zip(numbers, readings.positions, strict=True)):
        converted = to_deg_per_hour(values, body.unit)
        angle = (
            readings.angles_deg[slot]
            if readings.angles_deg is not None
            else nominal_angle(session, body.part, index)
        )
        rows.append(
            {
                "position": index,
                "n": int(values.size),
                "angle_deg": angle,
                "mean_deg_h": float(converted.mean()),
                "first": [float(v) for v in converted[:5]],
            }
        )
    language = request_language(request)
    notes = [translate(key, language, **params) for key, params in readings.left_out()]
    expected = [row["angle_deg"] for row in rows]
    if readings.header_angles is not None and turned_other_way(readings.header_angles, expected):
        notes.append(
            other_way_note(
                "csv.header_angles_other_way", readings.header_angles, expected, language
            )
        )
    elif readings.layout == "long" and readings.angles_deg is not None:  # used as given
        turns = [nominal_angle(session, body.part, k) for k in range(1, len(rows) + 1)]
        if turned_other_way(readings.angles_deg, turns):
            notes.append(
                other_way_note("csv.long_angles_other_way", readings.angles_deg, turns, language)
            )
    if single:
        notes.insert(0, translate("csv.one_position_record", language, position=first))
    notes += [translate(note["key"], language, **note["params"]) for note in parsed.notes]
    if parsed.columns:
        notes.insert(
            1,
            translate(
                "csv.record_columns", language, count=len(parsed.columns), column=parsed.column
            ),
        )
    return {
        "layout": readings.layout,
        "positions": rows,
        "notes": notes,
        "position_count": position_count(session),
        "columns": [
            {"value": column, "label": column_label(column, language)} for column in parsed.columns
        ],
        "column": parsed.column,
    }


def file_positions(session: LabSession, part: str, readings: Readings, first: int) -> list[int]:
    """The positions a file's readings are saved as: the record's chosen position; the
    numbers a file gives ("P3", "位置400" -- refused, as the save refuses it, where the
    session has no such position); the positions at the angles it gives, where each is
    one of the session's dial angles; else 1, 2, … in the file's order."""
    count = len(readings.positions)
    if readings.layout == "record":
        return [first]
    if readings.numbers is not None:
        for number in readings.numbers:  # the preview says so before the save does
            check_position(session, part, number)
        return list(readings.numbers)
    if readings.angles_deg is not None:
        dial = [(k, nominal_angle(session, part, k)) for k in range(1, position_count(session) + 1)]
        found = [
            next((k for k, at in dial if abs((angle - at + 180.0) % 360.0 - 180.0) < 1e-6), None)
            for angle in readings.angles_deg
        ]  # a revisit (1-2-3-4-4-3-2-1): its first position, so the file's order is kept
        if None not in found and len(set(found)) == count:
            return found
    return list(range(1, count + 1))


def other_way_note(key: str, header: list[float], session: list[float], language: str) -> str:
    """Said beside a preview whose file's angles run the other way from the session's: a
    header's (read in column order) or a long table's (used as given)."""
    return translate(
        key,
        language,
        header=angle_list(header),
        session=angle_list(session),
        count=len(session),
    )


def column_label(column: str, language: str) -> str:
    """A column as offered: its header cell, or "Column 3" where the file has no header."""
    return translate("csv.column_number", language, number=column) if column.isdigit() else column


@router.post("/sessions/{session_id}/csv", dependencies=[CsrfProtected, RowWriteSession])
def save_csv(
    session_id: ObjectId,
    user: CurrentUser,
    db: SessionDep,
    body: Annotated[CsvUpload, Body()],
):
    try:  # parsed before the first query takes the write lock; reported after the checks
        readings, problem = parse_csv_upload(body).readings, None
    except UserError as error:
        readings, problem = None, error
    session = recordable_session(db, user, session_id, InputMethod.csv)
    if problem is not None:
        raise problem
    check_position_count(len(readings.positions), position_count(session))

    if readings.layout == "record" and body.position is None:
        raise UserError("csv.record_position")
    numbers = file_positions(session, body.part, readings, body.position or 1)

    def numbered(items):
        return dict(zip(numbers, items, strict=True)) if items is not None else None

    saved = record_positions(
        db,
        session,
        part=body.part,
        unit=body.unit,
        columns=numbered(readings.positions),
        source=InputMethod.csv,
        angles=numbered(readings.angles_deg),
        times=numbered(readings.times_s),
        temperatures=numbered(readings.temperatures_c),
    )
    db.commit()
    return {"saved": saved}
