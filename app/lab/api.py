"""REST API v1: upload readings and read results from devices and scripts.

Authentication: ``Authorization: Bearer <token>`` (a personal access token from the
Tokens page, or a one-hour token from ``POST /api/v1/auth/token``); a browser session
cookie also works, with the CSRF token in ``X-CSRF-Token`` for changes.  Errors are
``{"detail": ...}`` with a 4xx status; objects the caller may not see answer 404.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from datetime import datetime
from typing import Annotated, Any, Literal

import numpy as np
from fastapi import APIRouter, Depends, Form, HTTPException, Path, Request
from fastapi.responses import JSONResponse, Response, StreamingResponse
from pydantic import BaseModel, ConfigDict, Field, StrictFloat, StrictInt, ValidationError
from sqlmodel import Session, select

from app.accounts.security import (
    log_in,
    tokens_match,
)
from app.accounts.service import may_reset_password, reset_password, teaches_student
from app.accounts.tokens import LOGIN_TOKEN_LIFETIME, check_token, count_cookie_request, new_token
from app.core.exceptions import GyroInputError
from app.core.jsonsafe import UnsafeJson, json_safe, loads_finite
from app.core.readings import NumberOutOfRange, parse_decimal
from app.core.units import canonical_unit, to_deg_per_hour
from app.db import statement_session
from app.lab import sessions as labsessions
from app.lab.sim import nominal_angle
from app.lab.store import (
    MAX_SAMPLES_PER_POSITION,
    POSITIONS,
    append_samples,
    current_takes,
    session_results,
    store_take,
    submit,
)
from app.models import Assignment, Course, LabSession, Role, User
from app.review.service import class_rows, export_rows
from app.web.deps import (
    MAX_ID,
    SAFE_METHODS,
    ObjectId,
    SessionDep,
    SettingsDep,
    load_login,
)
from app.web.exports import csv_table

MAX_UPLOAD_BYTES = 32 * 1024 * 1024  # 1e6 samples as JSON text are about 20 MB


class Error(BaseModel):
    detail: str | list = Field(description="what is wrong, in words (a list for 422)")


ERRORS: dict[int | str, dict[str, Any]] = {
    400: {"description": "Bad input (the message says what is wrong)", "model": Error},
    401: {"description": "Not authenticated", "model": Error},
    403: {
        "description": "Not allowed (role, token scope, CSRF or assignment rules)",
        "model": Error,
    },
    404: {"description": "No such object, or not yours", "model": Error},
    413: {"description": "Request body too large", "model": Error},
    422: {"description": "Wrong types or missing fields", "model": Error},
    429: {"description": "Too many requests", "model": Error},
}

router = APIRouter(prefix="/api/v1", tags=["api"], responses=ERRORS)


# --- authentication ------------------------------------------------------------------------


@dataclass
class Caller:
    user: User
    scopes: set[str]
    via: str  # token | cookie


def api_caller(request: Request, db: SessionDep, settings: SettingsDep) -> Caller:
    header = request.headers.get("authorization", "")
    if header.lower().startswith("bearer "):
        # Not a serialised writer: the count is one atomic UPDATE (see check_token); the
        # user is read alongside and handed to the request's session like a cookie login
        # (deps.load_login), so the write lock is taken by the handler alone.
        with statement_session() as counter_db:
            check = check_token(counter_db, header[7:].strip(), settings.api_rate_per_minute)
            counter_db.commit()
            found = counter_db.get(User, check.token.user_id) if check.token else None
            scopes = set(check.token.scopes.split(",")) if check.token else set()
        if check.problem == "invalid":
            raise HTTPException(
                401, "Invalid, revoked or expired token.", headers={"WWW-Authenticate": "Bearer"}
            )
        if check.problem == "rate":
            raise HTTPException(
                429,
                "Too many requests with this token; slow down.",
                headers={"Retry-After": str(check.retry_after)},
            )
        if found is None:
            raise HTTPException(401, "Invalid token.", headers={"WWW-Authenticate": "Bearer"})
        if found.must_change_password:
            raise HTTPException(
                403, "This account must change its initial password in the browser first."
            )
        return Caller(db.merge(found, load=False), scopes, "token")
    user = load_login(request, db, settings)
    if user is None:
        raise HTTPException(401, "Not authenticated.", headers={"WWW-Authenticate": "Bearer"})
    if request.method not in SAFE_METHODS and not tokens_match(
        request.state.auth.csrf_token, request.headers.get("x-csrf-token")
    ):
        raise HTTPException(403, "Missing or wrong X-CSRF-Token header.")
    if user.must_change_password:
        raise HTTPException(403, "Change your initial password first.")
    with statement_session() as counter_db:  # the same per-minute rate as a token
        wait = count_cookie_request(counter_db, request.state.auth.id, settings.api_rate_per_minute)
        counter_db.commit()
    if wait:
        raise HTTPException(
            429,
            "Too many requests from this session; slow down.",
            headers={"Retry-After": str(wait)},
        )
    return Caller(user, {"read", "upload"}, "cookie")


CallerDep = Annotated[Caller, Depends(api_caller)]


def need(caller: Caller, scope: str) -> None:
    if scope not in caller.scopes:
        raise HTTPException(403, f"This token lacks the '{scope}' scope.")


def need_teacher(caller: Caller) -> None:
    if caller.user.role != Role.teacher:
        raise HTTPException(403, "Only teachers may do this.")


class TokenOut(BaseModel):
    access_token: str
    token_type: Literal["bearer"] = "bearer"
    expires_in: int = Field(description="seconds")


@router.post("/auth/token", response_model=TokenOut, tags=["api: auth"])
def login_for_token(
    request: Request,
    db: SessionDep,
    settings: SettingsDep,
    username: Annotated[str, Form(min_length=1, max_length=200)],
    password: Annotated[str, Form(min_length=1, max_length=1000)],
):
    """OAuth2 password flow: a one-hour bearer token (read and upload), throttled like the
    log-in page."""
    address = request.client.host if request.client else "unknown"
    outcome = log_in(db, username, password, address, settings)
    if outcome.problem == "throttled":
        raise HTTPException(
            429,
            "Too many failed log-in attempts; wait and try again.",
            headers={"Retry-After": str(outcome.retry_after)},
        )
    if outcome.problem == "busy":
        raise HTTPException(
            503, "The server is busy checking passwords; try again.", headers={"Retry-After": "1"}
        )
    if outcome.user is None:
        raise HTTPException(
            401, "Wrong username or password.", headers={"WWW-Authenticate": "Bearer"}
        )
    user = outcome.user
    if user.must_change_password:
        db.commit()
        raise HTTPException(403, "Change your initial password in the browser first.")
    raw, _ = new_token(db, user, kind="login", lifetime=LOGIN_TOKEN_LIFETIME)
    db.commit()
    return TokenOut(access_token=raw, expires_in=int(LOGIN_TOKEN_LIFETIME.total_seconds()))


# --- models ---------------------------------------------------------------------------------


class MeOut(BaseModel):
    id: int
    username: str
    display_name: str
    role: str
    language: str | None


class Station(BaseModel):
    model_config = ConfigDict(strict=True, allow_inf_nan=False)
    latitude_deg: float = Field(ge=-90, le=90)
    earth_rate_deg_h: float = Field(gt=0, lt=1000, default=15.041)


class HeadingSettings(BaseModel):
    model_config = ConfigDict(strict=True, allow_inf_nan=False)
    rotation: Literal["ccw", "cw"] = "ccw"
    start_angle_deg: float = 0.0


class LatitudeSettings(BaseModel):
    model_config = ConfigDict(strict=True, allow_inf_nan=False)
    start_angle_deg: float = 0.0
    step_deg: float = 90.0


class SessionCreate(BaseModel):
    model_config = ConfigDict(
        strict=True,
        allow_inf_nan=False,
        json_schema_extra={
            "examples": [
                {
                    "title": "Bench 3, Tuesday",
                    "station": {"latitude_deg": 39.93, "earth_rate_deg_h": 15.04},
                    "heading": {"rotation": "ccw", "start_angle_deg": 0.0},
                    "latitude": {"start_angle_deg": 0.0, "step_deg": 90.0},
                }
            ]
        },
    )
    title: str = Field(default="", max_length=200)
    assignment_id: int | None = Field(default=None, ge=1, le=MAX_ID)
    station: Station | None = None
    heading: HeadingSettings = HeadingSettings()
    latitude: LatitudeSettings = LatitudeSettings()
    simulator_preset: str = Field(default="teaching-fog", max_length=32)
    symmetric_order: bool = Field(
        default=False,
        description="Record 1-2-3-4-4-3-2-1: positions 5–8 revisit 4–1, so a linear drift "
        "cancels (and, with times, is fitted).",
    )


class PositionSummary(BaseModel):
    part: str
    position: int
    angle_deg: float
    n_samples: int
    source: str
    recorded_at: datetime


class SessionOut(BaseModel):
    id: int
    title: str
    assignment_id: int | None
    status: str
    station: Station
    heading: HeadingSettings
    latitude: LatitudeSettings
    min_readings: int
    symmetric_order: bool
    positions: list[PositionSummary]
    created_at: datetime
    updated_at: datetime


class PositionUpload(BaseModel):
    model_config = ConfigDict(
        strict=True,
        allow_inf_nan=False,
        json_schema_extra={
            "examples": [
                {
                    "samples": [
                        10.74,
                        10.65,
                        10.84,
                        10.46,
                        10.65,
                        10.65,
                        10.74,
                        10.65,
                        10.84,
                        10.84,
                    ],
                    "unit": "deg/h",
                }
            ]
        },
    )
    samples: list[StrictFloat | StrictInt] = Field(
        min_length=1, max_length=MAX_SAMPLES_PER_POSITION
    )
    unit: Literal["deg/h", "deg/s", "rad/s"] = "deg/h"
    angle_deg: StrictFloat | StrictInt | None = Field(
        default=None, description="the dial angle; default: from the session's settings"
    )
    times_s: list[StrictFloat | StrictInt] | None = Field(
        default=None,
        max_length=MAX_SAMPLES_PER_POSITION,
        description="each sample's time in seconds, on one clock for the whole session "
        "(e.g. since switch-on): with the symmetric order the fit then estimates a linear "
        "bias drift",
    )
    offset: StrictInt | None = Field(
        default=None,
        ge=0,
        description="append only: index of the first sample, so a "
        "retried batch is not stored twice",
    )


class UploadOut(BaseModel):
    session_id: int
    part: str
    position: int
    n_samples: int = Field(description="samples now stored for this position")
    added: int


class HeadingOut(BaseModel):
    part: Literal["heading"]
    n_positions: int
    samples_per_position: list[int]
    position_means_deg_h: list[float]
    position_sems_deg_h: list[float | None]
    position_sigmas_deg_h: list[float] | None = Field(
        description="the 1σ(-equivalent) of each position mean that the result propagates"
    )
    azimuth_deg: float
    azimuth_sigma_deg: float | None
    theta_deg: float
    rotate_direction: Literal["clockwise", "counterclockwise"]
    rotate_deg: float
    then_axis_points: Literal["north", "south"]
    bias_deg_h: float
    amplitude_deg_h: float
    amplitude_sigma_deg_h: float | None
    closure_residual_deg_h: float | None
    closure_sigma_deg_h: float | None
    uncertainty_model: Literal["white", "closure", "allan"] | None = Field(
        description="what the 1σ assumes: white noise (Student-t), the closure residual "
        "(one degree of freedom), or the gyro's noise model"
    )
    drift_deg_h_per_h: float | None = Field(
        description="linear bias drift, fitted when 5+ positions have times on one clock"
    )
    drift_sigma_deg_h_per_h: float | None
    azimuth_error_deg: float | None


class LatitudeOut(BaseModel):
    part: Literal["latitude"]
    n_positions: int
    samples_per_position: list[int]
    position_means_deg_h: list[float]
    position_sems_deg_h: list[float | None]
    position_sigmas_deg_h: list[float] | None
    latitude_deg: float
    latitude_sigma_deg: float | None
    earth_rate_deg_h: float
    earth_rate_sigma_deg_h: float | None
    bias_deg_h: float
    latitude_error_percent: float | None
    latitude_error_deg: float | None = Field(description="φ − φ0 (°)")
    earth_rate_error_percent: float
    closure_residual_deg_h: float | None
    closure_sigma_deg_h: float | None
    uncertainty_model: Literal["white", "closure", "allan"] | None
    drift_deg_h_per_h: float | None
    drift_sigma_deg_h_per_h: float | None


class ResultsOut(BaseModel):
    heading: HeadingOut | None
    latitude: LatitudeOut | None
    problems: dict[str, str] = Field(default_factory=dict, description="why a part has no result")


class AttemptOut(BaseModel):
    session_id: int
    attempt: int
    submitted_at: datetime
    late: bool
    status: str


class CourseOut(BaseModel):
    id: int
    name: str
    archived: bool
    assignments: list[dict]


class SubmissionRow(BaseModel):
    username: str
    display_name: str
    status: str
    session_id: int | None
    attempts: int
    submitted_at: datetime | None
    late: bool
    results: dict
    heading_error_deg: float | None
    latitude_error_percent: float | None
    earth_rate_error_percent: float | None
    auto_check: bool | None
    grade: str | None


# --- helpers --------------------------------------------------------------------------------


def own(db: Session, caller: Caller, session_id: int) -> LabSession:
    try:
        return labsessions.own_session(db, caller.user, session_id)
    except labsessions.NotVisible:
        raise HTTPException(404, "No such session.") from None


def session_out(db: Session, session: LabSession) -> SessionOut:
    return SessionOut(
        id=session.id,
        title=session.title,
        assignment_id=session.assignment_id,
        status=session.status,
        station=Station(
            latitude_deg=session.latitude_deg, earth_rate_deg_h=session.earth_rate_deg_h
        ),
        heading=HeadingSettings(
            rotation=session.heading_rotation, start_angle_deg=session.heading_start_deg
        ),
        latitude=LatitudeSettings(
            start_angle_deg=session.latitude_start_deg, step_deg=session.latitude_step_deg
        ),
        min_readings=session.min_readings,
        symmetric_order=session.symmetric_order,
        positions=[
            PositionSummary(
                part=t.part,
                position=t.position,
                angle_deg=t.angle_deg,
                n_samples=t.n_samples,
                source=t.source,
                recorded_at=t.created_at,
            )
            for t in current_takes(db, session.id)
        ],
        created_at=session.created_at,
        updated_at=session.updated_at,
    )


def bad_input(error: GyroInputError) -> HTTPException:
    return HTTPException(413 if error.key == "lab.storage_full" else 400, str(error))


async def upload_body(request: Request) -> bytes:
    """The raw body (the only async step of an upload; parsing and storing run on the
    thread pool so that a 20 MB JSON body never stops the event loop)."""
    body = await request.body()
    if len(body) > MAX_UPLOAD_BYTES:
        raise HTTPException(413, f"The body is larger than {MAX_UPLOAD_BYTES} bytes.")
    return body


UploadBody = Annotated[bytes, Depends(upload_body)]


def read_upload(request: Request, body: bytes) -> PositionUpload:
    """A JSON PositionUpload, or text/csv: one value per line, or ``time_s,value``."""
    content_type = request.headers.get("content-type", "").split(";")[0].strip().lower()
    if content_type == "text/csv":
        return parse_csv_upload(
            body, request.query_params.get("unit", "deg/h"), request.query_params.get("angle_deg")
        )
    if content_type not in ("application/json", ""):
        raise HTTPException(415, "Send application/json or text/csv.")
    try:
        data = loads_finite(body)
    except UnsafeJson as error:
        raise HTTPException(400, str(error)) from None

    try:
        return PositionUpload.model_validate(data)
    except ValidationError as error:
        details = [
            {"loc": list(e["loc"]), "msg": e["msg"], "type": e["type"]} for e in error.errors()
        ]
        raise HTTPException(422, details) from None


def parse_csv_upload(body: bytes, unit: str, angle: str | None) -> PositionUpload:
    try:
        text = body.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise HTTPException(400, "The CSV is not UTF-8 text.") from None
    try:  # newline="": lines may end in \n, \r\n or a bare \r
        rows = list(csv.reader(io.StringIO(text, newline="")))
    except csv.Error as error:
        raise HTTPException(400, f"The CSV cannot be read: {error}.") from None
    values: list[float] = []
    times: list[float] = []
    for number, row in enumerate(rows, start=1):
        cells = [c.strip() for c in row if c.strip()]
        if not cells or cells[0].startswith("#"):
            continue
        try:
            numbers = [parse_decimal(c) for c in cells]
        except NumberOutOfRange:
            raise HTTPException(400, f"Line {number}: '{cells[0][:40]}' is out of range.") from None
        except ValueError:
            if number == 1 and not values:
                continue  # a header such as "time_s,value"
            raise HTTPException(
                400, f"Line {number}: '{','.join(cells)[:40]}' is not a number."
            ) from None
        if len(numbers) == 1:
            values.append(numbers[0])
        elif len(numbers) == 2:
            times.append(numbers[0])
            values.append(numbers[1])
        else:
            raise HTTPException(400, f"Line {number}: expected 'value' or 'time_s,value'.")
    if times and len(times) != len(values):
        raise HTTPException(400, "Give a time on every line or on none.")
    if not values:
        raise HTTPException(400, "The CSV has no readings.")
    try:
        unit = canonical_unit(unit)
    except GyroInputError as error:
        raise HTTPException(400, str(error)) from None
    try:
        angle_value = parse_decimal(angle.strip()) if angle is not None else None
    except ValueError:
        raise HTTPException(400, "angle_deg must be a finite number of degrees.") from None
    return PositionUpload(samples=values, unit=unit, times_s=times or None, angle_deg=angle_value)


def upload_arrays(upload: PositionUpload) -> tuple[np.ndarray, np.ndarray | None]:
    values = np.asarray(upload.samples, dtype=float)
    if not np.all(np.isfinite(values)):
        raise HTTPException(400, "Every sample must be a finite number.")
    times = None
    if upload.times_s is not None:
        times = np.asarray(upload.times_s, dtype=float)
        if times.size != values.size:
            raise HTTPException(400, "times_s must have one entry per sample.")
        if not np.all(np.isfinite(times)):
            raise HTTPException(400, "Every time must be a finite number.")
    return to_deg_per_hour(values, upload.unit), times


def require_api_method(db: Session, session: LabSession) -> None:
    if session.assignment_id is None:
        return
    assignment = db.get(Assignment, session.assignment_id)
    if assignment is None or not ({"csv", "manual"} & set(assignment.methods)):
        raise HTTPException(403, "This assignment does not allow uploaded readings.")


def prepare_upload(
    request: Request,
    body: bytes,
    db: Session,
    caller: Caller,
    session_id: int,
    part: str,
    position: int,
):
    """The checks and parsing shared by replacing and appending a position's readings."""
    need(caller, "upload")
    try:  # parsed before the first query takes the write lock; reported after the checks
        upload, problem = read_upload(request, body), None
        values, times = upload_arrays(upload)
    except (HTTPException, GyroInputError) as error:
        problem = error
    session = own(db, caller, session_id)
    require_api_method(db, session)
    if problem is not None:
        raise problem
    angle = (
        upload.angle_deg if upload.angle_deg is not None else nominal_angle(session, part, position)
    )
    return session, upload, values, times, float(angle)


PartPath = Annotated[Literal["heading", "latitude"], Path(description="heading | latitude")]
PositionPath = Annotated[int, Path(ge=1, le=POSITIONS)]
UPLOAD_BODY = {
    "requestBody": {
        "required": True,
        "content": {
            "application/json": {"schema": PositionUpload.model_json_schema()},
            "text/csv": {
                "schema": {
                    "type": "string",
                    "description": "one value per line, or time_s,value per line; an "
                    "optional header; ?unit= and ?angle_deg= in the URL",
                },
                "example": "time_s,value\n0,10.74\n1,10.65\n2,10.84\n",
            },
        },
    }
}


# --- routes ---------------------------------------------------------------------------------


@router.get("/me", response_model=MeOut)
def me(caller: CallerDep):
    """Who the token or session belongs to."""
    user = caller.user
    return MeOut(
        id=user.id,
        username=user.username,
        display_name=user.display_name,
        role=user.role,
        language=user.language,
    )


@router.get("/sessions", response_model=list[SessionOut])
def list_sessions(caller: CallerDep, db: SessionDep):
    """The caller's own lab sessions, newest first."""
    need(caller, "read")
    sessions = db.exec(
        select(LabSession)
        .where(LabSession.owner_id == caller.user.id)
        .order_by(LabSession.updated_at.desc())
    ).all()
    return [session_out(db, s) for s in sessions]


@router.post("/sessions", response_model=SessionOut, status_code=201)
def create_session(body: SessionCreate, caller: CallerDep, db: SessionDep):
    """Start a practice session (give ``station``) or the session of an assignment (give
    ``assignment_id``; asking again returns the same session)."""
    need(caller, "upload")
    assignment = None
    if body.assignment_id is not None:
        try:
            assignment = labsessions.visible_assignment(db, caller.user, body.assignment_id)
        except labsessions.NotVisible:
            raise HTTPException(404, "No such assignment.") from None
    elif body.station is None:
        raise HTTPException(400, "Give either station (practice) or assignment_id.")
    settings = labsessions.SessionSettings(
        title=body.title,
        latitude_deg=body.station.latitude_deg if body.station else None,
        earth_rate_deg_h=body.station.earth_rate_deg_h if body.station else None,
        rotation=body.heading.rotation,
        heading_start_deg=body.heading.start_angle_deg,
        latitude_start_deg=body.latitude.start_angle_deg,
        latitude_step_deg=body.latitude.step_deg,
        preset=body.simulator_preset,
        symmetric_order=body.symmetric_order,
    )
    try:
        session, created = labsessions.start_session(
            db, caller.user, settings, assignment, "API session"
        )
    except GyroInputError as error:
        raise bad_input(error) from None
    db.commit()
    return JSONResponse(
        session_out(db, session).model_dump(mode="json"), status_code=201 if created else 200
    )


@router.get("/sessions/{session_id}", response_model=SessionOut)
def get_session(session_id: ObjectId, caller: CallerDep, db: SessionDep):
    need(caller, "read")
    return session_out(db, own(db, caller, session_id))


@router.put(
    "/sessions/{session_id}/{part}/positions/{position}",
    response_model=UploadOut,
    openapi_extra=UPLOAD_BODY,
)
def put_position(
    request: Request,
    session_id: ObjectId,
    part: PartPath,
    position: PositionPath,
    body: UploadBody,  # read before the caller's lookup starts the write transaction
    caller: CallerDep,
    db: SessionDep,
):
    """Replace this position's readings (the previous take stays in the history).
    Atomic: on any error nothing is stored."""
    session, upload, values, times, angle = prepare_upload(
        request, body, db, caller, session_id, part, position
    )
    try:
        take = store_take(
            db,
            session,
            part=part,
            position=position,
            angle_deg=angle,
            values=values,
            times=times,
            source="api",
            unit=upload.unit,
        )
    except GyroInputError as error:
        db.rollback()
        raise bad_input(error) from None
    db.commit()
    return UploadOut(
        session_id=session.id,
        part=part,
        position=position,
        n_samples=take.n_samples,
        added=take.n_samples,
    )


@router.post(
    "/sessions/{session_id}/{part}/positions/{position}/samples",
    response_model=UploadOut,
    openapi_extra=UPLOAD_BODY,
)
def append_position(
    request: Request,
    session_id: ObjectId,
    part: PartPath,
    position: PositionPath,
    body: UploadBody,  # read before the caller's lookup starts the write transaction
    caller: CallerDep,
    db: SessionDep,
):
    """Append readings to this position (streaming devices).  With ``offset`` (the index
    of the first sample) a retried batch is stored once; a gap answers 409."""
    session, upload, values, times, angle = prepare_upload(
        request, body, db, caller, session_id, part, position
    )
    try:
        take, added = append_samples(
            db,
            session,
            part=part,
            position=position,
            angle_deg=angle,
            values=values,
            times=times,
            unit=upload.unit,
            offset=upload.offset,
        )
    except GyroInputError as error:
        db.rollback()
        if error.key == "lab.offset_gap":
            raise HTTPException(409, str(error)) from None
        raise bad_input(error) from None
    db.commit()
    return UploadOut(
        session_id=session.id, part=part, position=position, n_samples=take.n_samples, added=added
    )


@router.get("/sessions/{session_id}/results", response_model=ResultsOut)
def get_results(session_id: ObjectId, caller: CallerDep, db: SessionDep):
    """Exactly the keys of ``gyrolab solve --json`` per part (null without enough data)."""
    need(caller, "read")
    session = own(db, caller, session_id)
    results = session_results(db, session)
    payload: dict[str, Any] = {"problems": {}}
    for part, outcome in results.items():
        payload[part] = json_safe(outcome.to_json())
        if outcome.result is None and outcome.error is not None:
            payload["problems"][part] = str(outcome.error)
    return payload


@router.post("/sessions/{session_id}/submit", response_model=AttemptOut)
def submit_session(session_id: ObjectId, caller: CallerDep, db: SessionDep):
    """Freeze the data and results as a new attempt (the assignment's rules apply)."""
    need(caller, "upload")
    session = own(db, caller, session_id)
    try:
        attempt = submit(db, session)
    except GyroInputError as error:
        db.rollback()
        raise HTTPException(
            409 if error.key != "lab.nothing_to_submit" else 400, str(error)
        ) from None
    db.commit()
    return AttemptOut(
        session_id=session.id,
        attempt=attempt.number,
        submitted_at=attempt.submitted_at,
        late=attempt.late,
        status=session.status,
    )


@router.get("/courses", response_model=list[CourseOut], tags=["api: teachers"])
def list_courses(caller: CallerDep, db: SessionDep):
    """Teachers: their courses with the assignments in each."""
    need(caller, "read")
    need_teacher(caller)
    courses = db.exec(
        select(Course).where(Course.teacher_id == caller.user.id).order_by(Course.name)
    ).all()
    out = []
    for course in courses:
        assignments = db.exec(select(Assignment).where(Assignment.course_id == course.id)).all()
        out.append(
            CourseOut(
                id=course.id,
                name=course.name,
                archived=course.archived,
                assignments=[
                    {
                        "id": a.id,
                        "title": a.title,
                        "due_at": a.due_at.isoformat() if a.due_at else None,
                    }
                    for a in assignments
                ],
            )
        )
    return out


class NewPasswordOut(BaseModel):
    username: str
    initial_password: str = Field(description="one-time: the user must change it at log-in")


@router.post(
    "/users/{user_id}/reset-password", response_model=NewPasswordOut, tags=["api: teachers"]
)
def reset_user_password(user_id: ObjectId, caller: CallerDep, db: SessionDep):
    """Teachers and administrators: a new one-time password; every session and token of
    that user ends.  A teacher may reset only a student their own roster created and that
    no other teacher's course holds (anyone else: an administrator)."""
    need(caller, "upload")
    if caller.user.role not in (Role.teacher, Role.admin):
        raise HTTPException(403, "Only teachers and administrators may do this.")
    user = db.get(User, user_id)
    if user is None or (
        caller.user.role == Role.teacher and not teaches_student(db, caller.user, user)
    ):
        raise HTTPException(404, "No such user.")
    if not may_reset_password(db, caller.user, user):
        raise HTTPException(
            403,
            "You may reset only accounts your roster created and that no other teacher's "
            "course holds; ask an administrator.",
        )
    password = reset_password(db, user)
    db.commit()
    return NewPasswordOut(username=user.username, initial_password=password)


def teacher_assignment(db: Session, caller: Caller, assignment_id: int) -> Assignment:
    need(caller, "read")
    need_teacher(caller)
    assignment = db.get(Assignment, assignment_id)
    course = db.get(Course, assignment.course_id) if assignment else None
    if course is None or course.teacher_id != caller.user.id:
        raise HTTPException(404, "No such assignment.")
    return assignment


@router.get(
    "/assignments/{assignment_id}/submissions",
    response_model=list[SubmissionRow],
    tags=["api: teachers"],
)
def list_submissions(assignment_id: ObjectId, caller: CallerDep, db: SessionDep):
    """Teachers: one row per enrolled student with their latest submitted results."""
    assignment = teacher_assignment(db, caller, assignment_id)
    rows = []
    for row in class_rows(db, assignment):
        rows.append(
            SubmissionRow(
                username=row.student.username,
                display_name=row.student.display_name,
                status=row.status,
                session_id=row.session.id if row.session else None,
                attempts=len(row.attempts),
                submitted_at=row.submitted_at,
                late=row.late,
                results=row.results,
                heading_error_deg=row.check_error("heading"),
                latitude_error_percent=row.check_error("latitude"),
                earth_rate_error_percent=row.check_error("earth_rate"),
                auto_check=None if row.check is None else row.check.passed,
                grade=row.session.grade if row.session and row.session.status == "graded" else None,
            )
        )
    return rows


@router.get(
    "/assignments/{assignment_id}/export.csv",
    tags=["api: teachers"],
    response_class=Response,
    responses={200: {"content": {"text/csv": {}}, "description": "the class table"}},
)
def export_submissions(assignment_id: ObjectId, caller: CallerDep, db: SessionDep):
    """Teachers: the class table as CSV (UTF-8 with BOM)."""
    assignment = teacher_assignment(db, caller, assignment_id)
    return StreamingResponse(
        csv_table(export_rows(class_rows(db, assignment))), media_type="text/csv; charset=utf-8"
    )
