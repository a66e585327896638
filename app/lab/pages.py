"""The student lab: sessions, recording positions (by hand, CSV), results, submit, export."""

from __future__ import annotations

import json
import math
from datetime import datetime
from typing import Annotated, Literal

import numpy as np
from fastapi import APIRouter, Body, Form, HTTPException, Request
from fastapi.responses import JSONResponse, Response, StreamingResponse
from pydantic import BaseModel, Field, StrictFloat, StrictInt
from sqlmodel import Session, select

from app.core.exceptions import GyroInputError
from app.core.jsonsafe import json_safe
from app.core.readings import parse_readings_csv
from app.core.simulate import PRESETS
from app.core.units import EARTH_RATE_DEG_H, UNITS, canonical_unit, to_deg_per_hour
from app.lab import sessions as labsessions
from app.lab.charts import allan_figure, compass_figure, fit_figure, readings_figure
from app.lab.sim import FIRST_PASS, nominal_angle, north_dial_deg, position_count
from app.lab.store import (
    PARTS,
    POSITIONS,
    check_position,
    session_results,
    set_symmetric_order,
    store_take,
    submit,
    take_history,
)
from app.models import Assignment, Attempt, Course, Enrollment, LabSession, Role, User, utcnow
from app.review.service import auto_check, session_truth, truth_visible
from app.web.deps import (
    MAX_ID,
    CsrfProtected,
    CurrentUser,
    ObjectId,
    ReadOnlySessionDep,
    SessionDep,
)
from app.web.exports import Selection, readings_csv, session_json
from app.web.i18n import translator
from app.web.render import csrf_token_for, flash, redirect, render, request_language

router = APIRouter(prefix="/lab", tags=["pages: lab"], include_in_schema=False)

MAX_CSV_CHARS = 5_000_000
STATIONS = [  # practice presets: (key, latitude, Earth rate)
    ("handout", 39.93, 15.04),
    ("beijing", 39.99, EARTH_RATE_DEG_H),
    ("shanghai", 31.23, EARTH_RATE_DEG_H),
    ("xian", 34.26, EARTH_RATE_DEG_H),
    ("harbin", 45.75, EARTH_RATE_DEG_H),
    ("guangzhou", 23.13, EARTH_RATE_DEG_H),
]


STATION_VALUES = {key: (latitude, rate) for key, latitude, rate in STATIONS}


def own_session(db: Session, user: User, session_id: int) -> LabSession:
    """The caller's own session, else 404."""
    try:
        return labsessions.own_session(db, user, session_id)
    except labsessions.NotVisible:
        raise HTTPException(404) from None


def visible_assignment(db: Session, user: User, assignment_id: int) -> Assignment:
    try:
        return labsessions.visible_assignment(db, user, assignment_id)
    except labsessions.NotVisible:
        raise HTTPException(404) from None


def allowed_methods(db: Session, session: LabSession) -> list[str]:
    if session.assignment_id is None:
        return ["manual", "csv", "simulator"]
    assignment = db.get(Assignment, session.assignment_id)
    return assignment.methods if assignment else []


def require_method(db: Session, session: LabSession, method: str) -> None:
    if method not in allowed_methods(db, session):
        raise HTTPException(403, "This assignment does not allow that way of recording.")


def my_assignments(db: Session, user: User) -> list[tuple[Assignment, Course]]:
    if user.role == Role.teacher:
        query = select(Assignment, Course).join(Course).where(Course.teacher_id == user.id)
    else:
        query = (
            select(Assignment, Course)
            .join(Course)
            .join(Enrollment, Enrollment.course_id == Course.id)
            .where(Enrollment.student_id == user.id)
        )
    return list(
        db.exec(
            query.where(Course.archived == False).order_by(Assignment.created_at.desc())  # noqa: E712
        ).all()
    )


@router.get("")
def lab_home(request: Request, user: CurrentUser, db: SessionDep):
    sessions = db.exec(
        select(LabSession)
        .where(LabSession.owner_id == user.id)
        .order_by(LabSession.updated_at.desc())
    ).all()
    return render(
        request,
        "lab/home.html",
        {
            "sessions": sessions,
            "assignments": my_assignments(db, user),
            "stations": STATIONS,
            "presets": sorted(PRESETS),
            "now": utcnow(),
        },
    )


@router.post("/sessions", dependencies=[CsrfProtected])
def create_session(
    request: Request,
    user: CurrentUser,
    db: SessionDep,
    title: Annotated[str, Form(max_length=200)] = "",
    assignment_id: Annotated[int | None, Form(ge=1, le=MAX_ID)] = None,
    station: Annotated[str, Form(max_length=32)] = "handout",
    latitude_deg: Annotated[float | None, Form()] = None,
    earth_rate_deg_h: Annotated[float | None, Form()] = None,
    rotation: Annotated[Literal["ccw", "cw"], Form()] = "ccw",
    heading_start_deg: Annotated[float, Form()] = 0.0,
    latitude_start_deg: Annotated[float, Form()] = 0.0,
    latitude_step_deg: Annotated[float, Form()] = 90.0,
    preset: Annotated[str, Form(max_length=32)] = "teaching-fog",
):
    _ = translator(request_language(request))
    assignment = visible_assignment(db, user, assignment_id) if assignment_id is not None else None
    if assignment is None and station in STATION_VALUES:
        latitude_deg, earth_rate_deg_h = STATION_VALUES[station]
    settings = labsessions.SessionSettings(
        title=title,
        latitude_deg=latitude_deg,
        earth_rate_deg_h=earth_rate_deg_h,
        rotation=rotation,
        heading_start_deg=heading_start_deg,
        latitude_start_deg=latitude_start_deg,
        latitude_step_deg=latitude_step_deg,
        preset=preset,
    )
    try:
        session, created = labsessions.start_session(
            db, user, settings, assignment, _("lab.practice_title")
        )
    except GyroInputError as error:
        return _back_with_error(request, error.key)
    if created:
        db.commit()
    return redirect(f"/lab/sessions/{session.id}")


def _back_with_error(request: Request, key: str):
    response = redirect("/lab")
    flash(response, request, key, "error")
    return response


def _figures(results, _) -> dict[str, dict]:
    figures = {}
    for part, outcome in results.items():
        if outcome.positions:
            figures[f"{part}-readings"] = readings_figure(outcome, _)
        fit = fit_figure(outcome, _)
        if fit:
            figures[f"{part}-fit"] = fit
        allan = allan_figure(outcome, _)
        if allan:
            figures[f"{part}-allan"] = allan
    heading = results["heading"]
    if heading.result is not None:
        angles = [heading.positions[k].take.angle_deg for k in sorted(heading.positions)]
        figures["heading-compass"] = compass_figure(heading.result, angles, _)
    return figures


@router.get("/sessions/{session_id}")
def session_page(request: Request, session_id: ObjectId, user: CurrentUser, db: SessionDep):
    session = own_session(db, user, session_id)
    _ = translator(request_language(request))
    attempts = db.exec(
        select(Attempt).where(Attempt.session_id == session.id).order_by(Attempt.number)
    ).all()
    assignment = db.get(Assignment, session.assignment_id) if session.assignment_id else None
    config = {
        "sessionId": session.id,
        "csrf": csrf_token_for(request),
        "minReadings": session.min_readings,
        "table": {"heading": session.sim_table_heading, "latitude": session.sim_table_latitude},
        "plane": session.sim_plane_dial_deg,
        "messages": {key: _(key) for key in JS_MESSAGES},
    }
    editable = session.status != "graded" and not (
        session.assignment_id and session.status == "submitted"
    )
    return render(
        request,
        "lab/session.html",
        {
            **session_view(db, session, assignment, attempts, _),
            "history": take_history(db, session.id),
            "methods": allowed_methods(db, session),
            "units": UNITS,
            "unit_names": UNIT_NAMES,
            "plotly_url": request.app.state.plotly_url,
            "interrupted": session.stream_part,
            "config": config,
            "editable": editable,
            "reviewer": False,
        },
    )


def session_view(db: Session, session: LabSession, assignment, attempts, _) -> dict:
    """What both the student's page and the teacher's review show of a session."""
    results = session_results(db, session)
    nominal = {
        part: [nominal_angle(session, part, k) for k in range(1, position_count(session) + 1)]
        for part in PARTS
    }
    shows_feedback = session.status in ("returned", "graded")
    visible = truth_visible(session, assignment, len(attempts))
    truth = session_truth(db, session, assignment) if visible else None
    check = None
    if truth is not None and assignment is not None and attempts:
        check = auto_check(json.loads(attempts[-1].results_json), truth, assignment)
    heading = results["heading"]
    north = None
    if heading.result is not None:
        first = heading.positions[min(heading.positions)].take.angle_deg
        north = north_dial_deg(session, heading.result.azimuth_deg, first)
    return {
        "session": session,
        "north_dial": north,
        "results": results,
        "figures": _figures(results, _),
        "attempts": attempts,
        "assignment": assignment,
        "nominal": nominal,
        "drawing": drawing_coordinates(session),
        "positions": range(1, position_count(session) + 1),
        "preset": PRESETS.get(session.simulator_preset),
        "error_text": lambda error: error_text(error, _),
        "truth": truth,
        "check": check,
        "feedback": session.feedback if shows_feedback else "",
        "position_feedback": json.loads(session.feedback_positions or "{}")
        if shows_feedback
        else {},
        "grade": session.grade if session.status == "graded" else None,
        "attempt_results": [(a, json.loads(a.results_json)) for a in attempts],
    }


UNIT_NAMES = {"deg/h": "°/h", "deg/s": "°/s", "rad/s": "rad/s"}
JS_MESSAGES = (
    "js.not_a_number",
    "js.not_finite",
    "js.grid_ok",
    "js.grid_empty",
    "js.saving",
    "js.saved",
    "js.failed",
    "js.preview_title",
    "js.choose_file",
    "js.recording",
    "js.done",
    "js.connection_lost",
    "js.turned",
    "js.plane_set",
    "js.turn_needed",
    "js.position",
    "js.samples",
    "js.mean",
    "js.angle",
    "js.too_large",
    "chart.time_s",
    "chart.rate_deg_h",
    "js.pasted",
)


def error_text(error: GyroInputError, _) -> str:
    """A core error in the page's language (English text when no translation exists)."""
    return _(error.key, **error.params) if _known(error.key) else str(error)


def drawing_coordinates(session: LabSession) -> dict[str, dict[int, tuple]]:
    """Where each position's axis and label go on the 200×200 drawings."""
    out: dict[str, dict[int, tuple]] = {"heading": {}, "latitude": {}}
    for k in range(1, FIRST_PASS + 1):  # the return pass 5–8 revisits these
        relative = math.radians(nominal_angle(session, "heading", k) - session.heading_start_deg)
        sx, sy = math.sin(relative), -math.cos(relative)  # position 1 drawn pointing up
        out["heading"][k] = (
            round(100 + 70 * sx, 2),
            round(100 + 70 * sy, 2),
            round(100 + 90 * sx, 2),
            round(100 + 90 * sy, 2),
        )
        elevation = math.radians(nominal_angle(session, "latitude", k))
        cx, cy = math.cos(elevation), -math.sin(elevation)  # north to the right, zenith up
        out["latitude"][k] = (
            round(100 + 70 * cx, 2),
            round(100 + 70 * cy, 2),
            round(100 + 90 * cx, 2),
            round(100 + 90 * cy, 2),
        )
    return out


class ManualReadings(BaseModel):
    """Readings typed into the grid: one list per position (positions left empty are kept)."""

    part: Literal["heading", "latitude"]
    unit: str = "deg/h"
    columns: dict[int, Annotated[list[StrictFloat | StrictInt], Field(max_length=100_000)]] = Field(
        max_length=POSITIONS
    )


def _json_error(error: GyroInputError, request: Request, status: int = 400) -> JSONResponse:
    from app.web.i18n import translate

    language = request_language(request)
    message = translate(error.key, language, **error.params) if _known(error.key) else str(error)
    if error.key == "lab.storage_full":
        status = 413
    return JSONResponse(
        {"detail": message, "key": error.key, "params": error.params}, status_code=status
    )


def _known(key: str) -> bool:
    from app.web.messages import MESSAGES

    return key in MESSAGES


def _store_columns(
    db: Session,
    session: LabSession,
    part: str,
    unit: str,
    columns: dict[int, np.ndarray],
    source: str,
    angles: dict[int, float] | None = None,
    times: dict[int, np.ndarray] | None = None,
) -> list[int]:
    unit = canonical_unit(unit)
    saved = []
    for position, values in sorted(columns.items()):
        check_position(session, part, position)
        angle = (angles or {}).get(position, nominal_angle(session, part, position))
        store_take(
            db,
            session,
            part=part,
            position=position,
            angle_deg=angle,
            values=to_deg_per_hour(values, unit),
            times=(times or {}).get(position),
            source=source,
            unit=unit,
        )
        saved.append(position)
    return saved


@router.post("/sessions/{session_id}/manual", dependencies=[CsrfProtected])
def save_manual(
    request: Request,
    session_id: ObjectId,
    user: CurrentUser,
    db: SessionDep,
    body: Annotated[ManualReadings, Body()],
):
    session = own_session(db, user, session_id)
    require_method(db, session, "manual")
    columns = {k: np.asarray(v, dtype=float) for k, v in body.columns.items() if len(v)}
    try:
        if not columns:
            raise GyroInputError("readings.none", "Type at least one reading.")
        saved = _store_columns(db, session, body.part, body.unit, columns, "manual")
    except GyroInputError as error:
        db.rollback()
        return _json_error(error, request)
    db.commit()
    return {"saved": saved}


class CsvUpload(BaseModel):
    part: Literal["heading", "latitude"]
    unit: str = "deg/h"
    text: str


def _parse_upload(body: CsvUpload):
    if len(body.text) > MAX_CSV_CHARS:
        raise GyroInputError(
            "lab.file_too_large",
            "The file is larger than 5 MB.",
            limit_mb=MAX_CSV_CHARS // 1_000_000,
        )
    readings = parse_readings_csv(body.text, part=body.part)
    _check_position_count(len(readings.positions), POSITIONS)
    canonical_unit(body.unit)
    return readings


def _check_position_count(count: int, limit: int) -> None:
    """A file's positions fit the session: 4, or 8 in the symmetric order."""
    if count > limit:
        raise GyroInputError(
            "lab.too_many_positions",
            f"The file has {count} positions; at most {limit} "
            "(8 in the symmetric order 1-2-3-4-4-3-2-1).",
            count=count,
            limit=limit,
        )


@router.post("/sessions/{session_id}/csv/preview", dependencies=[CsrfProtected])
def preview_csv(
    request: Request,
    session_id: ObjectId,
    user: CurrentUser,
    db: ReadOnlySessionDep,
    body: Annotated[CsvUpload, Body()],
):
    session = own_session(db, user, session_id)
    require_method(db, session, "csv")
    try:
        readings = _parse_upload(body)
        _check_position_count(len(readings.positions), position_count(session))
    except GyroInputError as error:
        return _json_error(error, request)
    rows = []
    for index, values in enumerate(readings.positions, start=1):
        converted = to_deg_per_hour(values, body.unit)
        angle = (
            readings.angles_deg[index - 1]
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
    return {"layout": readings.layout, "positions": rows}


@router.post("/sessions/{session_id}/csv", dependencies=[CsrfProtected])
def save_csv(
    request: Request,
    session_id: ObjectId,
    user: CurrentUser,
    db: SessionDep,
    body: Annotated[CsvUpload, Body()],
):
    try:  # parsed before the first query takes the write lock; reported after the checks
        readings, problem = _parse_upload(body), None
    except GyroInputError as error:
        readings, problem = None, error
    session = own_session(db, user, session_id)
    require_method(db, session, "csv")
    if problem is not None:
        db.rollback()
        return _json_error(problem, request)
    try:
        _check_position_count(len(readings.positions), position_count(session))
        columns = dict(enumerate(readings.positions, start=1))
        angles = (
            dict(enumerate(readings.angles_deg, start=1))
            if readings.angles_deg is not None
            else None
        )
        times = dict(enumerate(readings.times_s, start=1)) if readings.times_s is not None else None
        saved = _store_columns(db, session, body.part, body.unit, columns, "csv", angles, times)
    except GyroInputError as error:
        db.rollback()
        return _json_error(error, request)
    db.commit()
    return {"saved": saved}


class Turn(BaseModel):
    part: Literal["heading", "latitude"]
    position: int = Field(ge=1, le=POSITIONS)


@router.post("/sessions/{session_id}/turn", dependencies=[CsrfProtected])
def turn_table(
    session_id: ObjectId, user: CurrentUser, db: SessionDep, body: Annotated[Turn, Body()]
):
    """Turn the virtual turntable; every real turn gets a new indexing error."""
    session = own_session(db, user, session_id)
    require_method(db, session, "simulator")
    try:
        check_position(session, body.part, body.position)
    except GyroInputError as error:
        raise HTTPException(400, str(error)) from error
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


class Plane(BaseModel):
    dial_deg: float = Field(ge=-360, le=360, allow_inf_nan=False)


@router.post("/sessions/{session_id}/plane", dependencies=[CsrfProtected])
def set_plane(
    session_id: ObjectId, user: CurrentUser, db: SessionDep, body: Annotated[Plane, Body()]
):
    """Turn the horizontal dial for part B: the gyro then turns in that vertical plane
    (north if part A's result was right, as at the real bench)."""
    session = own_session(db, user, session_id)
    require_method(db, session, "simulator")
    session.sim_plane_dial_deg = round(body.dial_deg, 3)
    session.sim_turns += 1
    db.add(session)
    db.commit()
    return {"dial_deg": session.sim_plane_dial_deg}


@router.post("/sessions/{session_id}/order", dependencies=[CsrfProtected])
def set_order(
    request: Request,
    session_id: ObjectId,
    user: CurrentUser,
    db: SessionDep,
    symmetric: Annotated[str, Form(max_length=8)] = "",
):
    """Record in the order 1-2-3-4 or the symmetric 1-2-3-4-4-3-2-1 (positions 5–8)."""
    session = own_session(db, user, session_id)
    response = redirect(f"/lab/sessions/{session.id}")
    try:
        if symmetric not in ("on", "off"):
            raise GyroInputError("lab.bad_order", "Choose the order: on or off.")
        set_symmetric_order(db, session, symmetric == "on")
    except GyroInputError as error:
        db.rollback()
        flash(response, request, error.key, "error")
        return response
    db.commit()
    flash(response, request, "lab.order_symmetric" if symmetric == "on" else "lab.order_plain")
    return response


@router.get("/sessions/{session_id}/results.json")
def results_endpoint(session_id: ObjectId, user: CurrentUser, db: SessionDep):
    session = own_session(db, user, session_id)
    results = session_results(db, session)
    payload = {part: outcome.to_json() for part, outcome in results.items()}
    return Response(json.dumps(json_safe(payload)), media_type="application/json")


@router.post("/sessions/{session_id}/submit", dependencies=[CsrfProtected])
def submit_session(request: Request, session_id: ObjectId, user: CurrentUser, db: SessionDep):
    session = own_session(db, user, session_id)
    response = redirect(f"/lab/sessions/{session.id}")
    try:
        attempt = submit(db, session)
    except GyroInputError as error:
        db.rollback()
        flash(response, request, error.key, "error")
        return response
    db.commit()
    flash(response, request, "lab.submitted", "success", number=attempt.number)
    return response


@router.get("/sessions/{session_id}/export.csv")
def export_session_csv(session_id: ObjectId, user: CurrentUser, db: SessionDep):
    session = own_session(db, user, session_id)
    return StreamingResponse(
        readings_csv(Selection(session.id)),
        media_type="text/csv; charset=utf-8",
        headers=_download(session, "csv"),
    )


@router.get("/sessions/{session_id}/export.json")
def export_session_json(session_id: ObjectId, user: CurrentUser, db: SessionDep):
    session = own_session(db, user, session_id)
    return StreamingResponse(
        session_json(Selection(session.id)),
        media_type="application/json",
        headers=_download(session, "json"),
    )


def _download(session: LabSession, extension: str) -> dict[str, str]:
    stamp = datetime.now().strftime("%Y%m%d")
    return {
        "Content-Disposition": f'attachment; filename="gyrolab-session-{session.id}-'
        f'{stamp}.{extension}"'
    }
