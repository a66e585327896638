"""The student lab's actions on a session: record positions (grid, CSV), turn the virtual
table, choose the order, read results, submit and download.  Each calls the lab service."""

from __future__ import annotations

import json
from datetime import datetime
from typing import Annotated

import numpy as np
from fastapi import APIRouter, Body, Depends, Form, Query, Request
from fastapi.responses import Response, StreamingResponse

from app.accounts.deps import CsrfProtected, CurrentUser
from app.core.exceptions import UserError
from app.core.jsonsafe import json_safe
from app.core.position_records import (
    RECORD_PROBLEMS,
    OnePositionRecord,
    parse_one_position_record,
)
from app.core.readings import parse_readings_csv
from app.core.readings_data import Readings
from app.core.static_record import names_its_columns_in_a_comment
from app.core.units import canonical_unit, to_deg_per_hour
from app.core.workbook_text import workbook_readings
from app.lab.deps import OwnedSession, OwnSessionId
from app.lab.exports import Selection, readings_csv, session_json
from app.lab.grid import grid_readings
from app.lab.result_cache import results_of
from app.lab.schemas import CsvUpload, ManualReadings, Plane, Trim, Turn
from app.lab.service import own_session, record_positions, recordable_session
from app.lab.sim import nominal_angle, position_count, wait_for_gyro, warm_up_state
from app.lab.store import POSITIONS, check_position, current_takes, set_symmetric_order
from app.lab.submissions import submit
from app.lab.trim import trim_position
from app.models import InputMethod, LabSession, Part
from app.web.deps import ObjectId, ReadOnlySession, RowWriteSession, SessionDep
from app.web.exports import attachment
from app.web.i18n import translate
from app.web.render import flash, redirect, request_language
from app.web.work_slots import held_while_streaming, pool

router = APIRouter(prefix="/lab", tags=["pages: lab"], include_in_schema=False)
# A route that changes a session reads it in its handler, after ``OwnSessionId`` checked
# it is the caller's (lab.deps: why).

MAX_CSV_CHARS = 5_000_000
MAX_WORKBOOK_BYTES = 5_000_000  # as a CSV file chosen on the page (lab.js MAX_FILE_BYTES)


@router.post("/sessions/{session_id}/manual", dependencies=[CsrfProtected, RowWriteSession])
def save_manual(
    session_id: OwnSessionId,
    user: CurrentUser,
    db: SessionDep,
    body: Annotated[ManualReadings, Body()],
):
    session = recordable_session(db, user, session_id, InputMethod.manual)
    columns = {k: np.asarray(v, dtype=float) for k, v in body.columns.items() if len(v)}
    if not columns:
        raise UserError("readings.none")
    saved = record_positions(
        db, session, part=body.part, unit=body.unit, columns=columns, source=InputMethod.manual
    )
    db.commit()
    return {"saved": saved}


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
    if body.column is not None or names_its_columns_in_a_comment(body.text):
        # a column chosen, or a header behind '#' (an IMU's record): a record's file only
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


async def workbook_body(request: Request) -> bytes:
    """A workbook's bytes, as the page sends them (the only async step: reading them)."""
    data = await request.body()
    if len(data) > MAX_WORKBOOK_BYTES:
        raise UserError("lab.file_too_large", limit_mb=MAX_WORKBOOK_BYTES // 1_000_000)
    return data


@router.post("/sessions/{session_id}/csv/workbook", dependencies=[CsrfProtected, ReadOnlySession])
def workbook_as_text(
    session_id: ObjectId,
    user: CurrentUser,
    db: SessionDep,
    data: Annotated[bytes, Depends(workbook_body)],
    part: Annotated[Part, Query()] = Part.heading,
    sheet: Annotated[str | None, Query(min_length=1, max_length=100)] = None,
):
    """An Excel workbook chosen as the file: its sheet of readings (``sheet``, else the
    one for ``part``) as the text the page then previews and saves as a CSV file's, and the
    sheets that hold readings, to choose from
    (:func:`app.core.workbook_text.workbook_readings`)."""
    recordable_session(db, user, session_id, InputMethod.csv)
    with pool("workbooks").slot(user.id):
        book = workbook_readings(data, sheet, part.value)
    if len(book.text) > MAX_CSV_CHARS:
        raise UserError("lab.file_too_large", limit_mb=MAX_CSV_CHARS // 1_000_000)
    return {"text": book.text, "sheet": book.sheet, "sheets": list(book.sheets)}


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
    numbers a long file gives ("P3"); the positions at the angles it gives, where each
    is one of the session's dial angles; else 1, 2, … in the file's order."""
    count = len(readings.positions)
    if readings.layout == "record":
        return [first]
    if readings.numbers is not None:
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


@router.post("/sessions/{session_id}/turn", dependencies=[CsrfProtected, RowWriteSession])
def turn_table(
    session_id: OwnSessionId, user: CurrentUser, db: SessionDep, body: Annotated[Turn, Body()]
):
    """Turn the virtual turntable; every real turn gets a new indexing error."""
    session = recordable_session(db, user, session_id, InputMethod.simulator)
    check_position(session, body.part, body.position)
    field = f"sim_table_{body.part}"
    if getattr(session, field) != body.position:
        setattr(session, field, body.position)
        session.sim_turns += 1
        db.add(session)
        db.commit()
    return {
        "part": body.part,
        "position": body.position,
        "dial_angle_deg": nominal_angle(session, body.part, body.position),
    }


@router.post("/sessions/{session_id}/trim", dependencies=[CsrfProtected, RowWriteSession])
def trim_recording(
    session_id: OwnSessionId, user: CurrentUser, db: SessionDep, body: Annotated[Trim, Body()]
):
    """Leave out the first readings of a position (the transient after turning the table):
    stored as a trim, no sample deleted."""
    session = own_session(db, user, session_id)
    take = trim_position(db, session, part=body.part, position=body.position, trim=body.trim)
    db.commit()
    return {"trim_start": take.trim_start, "n_used": take.n_samples - take.trim_start}


@router.post("/sessions/{session_id}/plane", dependencies=[CsrfProtected, RowWriteSession])
def set_plane(
    session_id: OwnSessionId, user: CurrentUser, db: SessionDep, body: Annotated[Plane, Body()]
):
    """Turn the horizontal dial for part B: the gyro then turns in that vertical plane
    (north if part A's result was right, as at the real bench)."""
    session = recordable_session(db, user, session_id, InputMethod.simulator)
    session.sim_plane_dial_deg = round(body.dial_deg, 3)
    session.sim_turns += 1
    db.add(session)
    db.commit()
    return {"dial_deg": session.sim_plane_dial_deg}


@router.post("/sessions/{session_id}/order", dependencies=[CsrfProtected, RowWriteSession])
def set_order(
    request: Request,
    session_id: OwnSessionId,
    user: CurrentUser,
    db: SessionDep,
    symmetric: Annotated[str, Form(max_length=8)] = "",
):
    """Record in the order 1-2-3-4 or the symmetric 1-2-3-4-4-3-2-1 (positions 5–8)."""
    session = own_session(db, user, session_id)
    response = redirect(f"/lab/sessions/{session.id}")
    try:
        if symmetric not in ("on", "off"):
            raise UserError("lab.bad_order")
        set_symmetric_order(db, session, symmetric == "on")
    except UserError as error:
        db.rollback()
        flash(response, request, error.key, "error")
        return response
    db.commit()
    flash(response, request, "lab.order_symmetric" if symmetric == "on" else "lab.order_plain")
    return response


@router.post("/sessions/{session_id}/wait", dependencies=[CsrfProtected, RowWriteSession])
def wait_for_warm_up(
    request: Request,
    session_id: OwnSessionId,
    user: CurrentUser,
    db: SessionDep,
    minutes: Annotated[str, Form(max_length=8)] = "",
):
    """Let the simulated gyro warm up: its clock runs on by the minutes asked (1–60)."""
    session = recordable_session(db, user, session_id, InputMethod.simulator)
    response = redirect(f"/lab/sessions/{session.id}#sim-warm-up")
    try:
        wanted = int(minutes)
    except ValueError:
        wanted = 0
    if not 1 <= wanted <= 60:
        flash(response, request, "sim.bad_wait", "error")
        return response
    wait_for_gyro(session, wanted * 60.0)
    db.add(session)
    db.commit()
    state = warm_up_state(session)
    flash(response, request, "sim.waited", "success", minutes=state["on_minutes"])
    return response


@router.get("/sessions/{session_id}/grid.json")
def grid_endpoint(session: OwnedSession, db: SessionDep, part: Part = Part.heading):
    """The saved readings of one part, for the typed grid to load back for editing."""
    return grid_readings(db, session, part)


@router.get("/sessions/{session_id}/results.json")
def results_endpoint(session: OwnedSession, db: SessionDep):
    results = results_of(db, session)
    payload = {part: outcome.to_json() for part, outcome in results.items()}
    return Response(json.dumps(json_safe(payload)), media_type="application/json")


@router.post("/sessions/{session_id}/submit", dependencies=[CsrfProtected, RowWriteSession])
def submit_session(request: Request, session_id: OwnSessionId, user: CurrentUser, db: SessionDep):
    session = own_session(db, user, session_id)
    response = redirect(f"/lab/sessions/{session.id}")
    try:
        attempt = submit(db, session)
    except UserError as error:
        db.rollback()
        flash(response, request, error.key, "error")
        return response
    db.commit()
    flash(response, request, "lab.submitted", "success", number=attempt.number)
    return response


@router.get("/sessions/{session_id}/export.csv")
def export_session_csv(session: OwnedSession, user: CurrentUser):
    return StreamingResponse(
        held_while_streaming("exports", user.id, readings_csv(Selection(session.id))),
        media_type="text/csv; charset=utf-8",
        headers=download_headers(session, user.username, "csv"),
    )


@router.get("/sessions/{session_id}/export.json")
def export_session_json(session: OwnedSession, user: CurrentUser):
    return StreamingResponse(
        held_while_streaming("exports", user.id, session_json(Selection(session.id))),
        media_type="application/json",
        headers=download_headers(session, user.username, "json"),
    )


def download_headers(session: LabSession, owner: str, extension: str) -> dict[str, str]:
    """The session's download named after it and its student: "<title>_<username>_<date>"."""
    stamp = datetime.now().strftime("%Y%m%d")
    return {"Content-Disposition": attachment([session.title, owner, stamp], extension)}
