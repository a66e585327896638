"""REST API v1, the lab: sessions, uploading a position's readings, results, submitting.

Authentication: ``Authorization: Bearer <token>`` (a personal access token from the
Tokens page, or a one-hour token from ``POST /api/v1/auth/token``); a browser session
cookie also works, with the CSRF token in ``X-CSRF-Token`` for changes
(:mod:`app.accounts.api_auth`).  Errors are ``{"detail": ..., "key": ...}`` with a 4xx
status, in the language of ``Accept-Language``; objects the caller may not see answer 404.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from fastapi import APIRouter, Depends, Path, Request
from fastapi.responses import JSONResponse, Response
from sqlmodel import Session, select

from app.accounts.api_auth import Caller, ReadCaller, UploadCaller, api_caller, require_scope
from app.core.exceptions import UserError
from app.core.jsonsafe import json_safe
from app.db import read_session
from app.lab import sessions as labsessions
from app.lab.partners import in_sessions_of
from app.lab.planner import session_plan
from app.lab.result_cache import CachedResults, cached_results
from app.lab.results_read import cached_results_for_token
from app.lab.schemas import (
    AttemptOut,
    HeadingSettings,
    LatitudeSettings,
    PlanOut,
    PositionSummary,
    PositionUpload,
    ResultsOut,
    SessionCreate,
    SessionOut,
    Station,
    TrimIn,
    TrimOut,
    UploadOut,
)
from app.lab.service import append_readings, own_session, record_position, recordable_session
from app.lab.store import POSITIONS, current_takes
from app.lab.submissions import submit
from app.lab.trim import trim_position
from app.lab.uploads import Upload
from app.models import InputMethod, LabSession
from app.web.deps import ObjectId, RowWriteSession, SessionDep, SettingsDep
from app.web.errors import API_ERRORS
from app.web.i18n import translate

router = APIRouter(prefix="/api/v1", tags=["api"], responses=API_ERRORS)


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


def own_session_id(session_id: ObjectId, caller: UploadCaller) -> int:
    """The id of the caller's own session (404 for anyone else's), checked without the
    write lock (see lab.deps.OwnSessionId)."""
    with read_session() as db:
        own_session(db, caller.user, session_id)
    return session_id


CallersSessionId = Annotated[int, Depends(own_session_id)]


def uploadable_session(db: Session, caller: Caller, session_id: int) -> LabSession:
    """The caller's own session, when its assignment allows uploaded readings (read in the
    handler, not a dependency: see lab.deps)."""
    return recordable_session(db, caller.user, session_id, InputMethod.api)


def readable_session(session_id: ObjectId, caller: ReadCaller, db: SessionDep) -> LabSession:
    return own_session(db, caller.user, session_id)


ReadableSession = Annotated[LabSession, Depends(readable_session)]


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
                    "optional header; a gyro logger's own file; ?unit= and ?angle_deg= "
                    "(and for appends ?offset=) in the URL; ?column= for one axis of an "
                    "IMU's file (a header name or a number from 1)",
                },
                "example": "time_s,value\n0,10.74\n1,10.65\n2,10.84\n",
            },
            "application/octet-stream": {
                "schema": {
                    "type": "string",
                    "format": "binary",
                    "description": "raw little-endian floats: ?dtype=float64 (default) or "
                    "float32, ?columns=2 for time_s,value pairs; or a NumPy .npy file "
                    "(shape (n,) or (n, 2)); ?unit=, ?angle_deg=, ?offset= as for CSV",
                }
            },
        },
    }
}


# --- routes ---------------------------------------------------------------------------------


@router.get("/sessions", response_model=list[SessionOut])
def list_sessions(caller: ReadCaller, db: SessionDep):
    """The caller's own lab sessions and those shared as a lab partner, newest first."""
    sessions = db.exec(
        select(LabSession)
        .where(in_sessions_of(caller.user.id))
        .order_by(LabSession.updated_at.desc())
    ).all()
    return [session_out(db, s) for s in sessions]


@router.post(
    "/sessions",
    response_model=SessionOut,
    status_code=201,
    dependencies=[RowWriteSession],
)
def create_session(body: SessionCreate, caller: UploadCaller, db: SessionDep):
    """Start a practice session (give ``station``) or the session of an assignment (give
    ``assignment_id``; asking again returns the same session)."""
    assignment = None
    if body.assignment_id is not None:
        assignment = labsessions.visible_assignment(db, caller.user, body.assignment_id)
    elif body.station is None:
        raise UserError("api.station_or_assignment")
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
    session, created = labsessions.start_session(
        db, caller.user, settings, assignment, "API session"
    )
    db.commit()
    return JSONResponse(
        session_out(db, session).model_dump(mode="json"), status_code=201 if created else 200
    )


@router.get("/sessions/{session_id}", response_model=SessionOut)
def get_session(session: ReadableSession, db: SessionDep):
    return session_out(db, session)


@router.put(
    "/sessions/{session_id}/{part}/positions/{position}",
    response_model=UploadOut,
    openapi_extra=UPLOAD_BODY,
    dependencies=[RowWriteSession],
)
def put_position(
    session_id: CallersSessionId,
    part: PartPath,
    position: PositionPath,
    upload: Upload,
    caller: UploadCaller,
    db: SessionDep,
):
    """Replace this position's readings (the previous take stays in the history).
    Atomic: on any error nothing is stored."""
    session = uploadable_session(db, caller, session_id)
    upload.checked()
    take = record_position(
        db,
        session,
        part=part,
        position=position,
        values=upload.values,
        times=upload.times,
        unit=upload.upload.unit,
        angle_deg=upload.upload.angle_deg,
        source=InputMethod.api,
        temperatures=upload.temperatures,
    )
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
    dependencies=[RowWriteSession],
)
def append_position(
    session_id: CallersSessionId,
    part: PartPath,
    position: PositionPath,
    upload: Upload,
    caller: UploadCaller,
    db: SessionDep,
):
    """Append readings to this position (streaming devices).  With ``offset`` (the index
    of the first sample) a retried batch is stored once; a gap answers 409."""
    session = uploadable_session(db, caller, session_id)
    upload.checked()
    take, added = append_readings(
        db,
        session,
        part=part,
        position=position,
        values=upload.values,
        times=upload.times,
        unit=upload.upload.unit,
        angle_deg=upload.upload.angle_deg,
        offset=upload.upload.offset,
        temperatures=upload.temperatures,
    )
    db.commit()
    return UploadOut(
        session_id=session.id, part=part, position=position, n_samples=take.n_samples, added=added
    )


def session_results_entry(
    request: Request, session_id: ObjectId, settings: SettingsDep
) -> CachedResults:
    """The caller, their session and its cached results, in one trip to the thread pool
    (the route itself is async and does no I/O): the hot read path of devices and
    dashboards polling for results (issue 32)."""
    entry = cached_results_for_token(
        request.headers.get("authorization", ""), session_id, settings.api_rate_per_minute
    )
    if entry is not None:
        return entry
    with read_session() as db:
        caller = require_scope(api_caller(request, db, settings), "read")
        return cached_results(db, own_session(db, caller.user, session_id))


@router.get("/sessions/{session_id}/plan", response_model=PlanOut)
def get_plan(session: ReadableSession, db: SessionDep):
    """The accuracy planner of the session's station: the expected 1σ of the heading, the
    latitude and the Earth rate for each dwell per position, four positions or the
    symmetric eight, from the gyro's noise model (the teacher's Allan characterisation of
    the station, else the simulated gyro's preset)."""
    return session_plan(db, session).to_json()


@router.get("/sessions/{session_id}/results", response_model=ResultsOut)
async def get_results(entry: Annotated[CachedResults, Depends(session_results_entry)]):
    """Exactly the keys of ``gyrolab solve --json`` per part (null without enough data),
    with why a part has none (``problems``) and each part's data-quality flags (``flags``),
    in English."""
    return Response(results_body(entry), media_type="application/json")


def results_body(entry: CachedResults) -> bytes:
    """The response body of a cached result, validated and serialised once."""
    if entry.payload is None:
        payload: dict[str, Any] = {"problems": {}, "flags": {}}
        for part, outcome in entry.parts.items():
            payload[part] = json_safe(outcome.to_json())
            if outcome.result is None and outcome.error is not None:
                # in English: one cached body serves every reader
                error = outcome.error
                payload["problems"][part] = translate(error.key, "en", **error.params)
            if outcome.flags:
                payload["flags"][part] = [
                    {**flag, "message": translate(flag["key"], "en", **flag["params"])}
                    for flag in outcome.flags
                ]
        entry.payload = ResultsOut.model_validate(payload).model_dump_json().encode()
    return entry.payload


@router.put(
    "/sessions/{session_id}/{part}/positions/{position}/trim",
    response_model=TrimOut,
    dependencies=[RowWriteSession],
)
def put_trim(
    part: PartPath,
    position: PositionPath,
    body: TrimIn,
    session_id: CallersSessionId,
    caller: UploadCaller,
    db: SessionDep,
):
    """Leave out the first ``trim`` readings of a position (the transient after turning the
    table); 0 restores them.  Stored as a trim on the take: no sample is deleted."""
    session = own_session(db, caller.user, session_id)
    take = trim_position(db, session, part=part, position=position, trim=body.trim)
    db.commit()
    return TrimOut(
        part=part,
        position=position,
        n_samples=take.n_samples,
        trim_start=take.trim_start,
        n_used=take.n_samples - take.trim_start,
    )


@router.post(
    "/sessions/{session_id}/submit", response_model=AttemptOut, dependencies=[RowWriteSession]
)
def submit_session(session_id: CallersSessionId, caller: UploadCaller, db: SessionDep):
    """Freeze the data and results as a new attempt (the assignment's rules apply)."""
    session = own_session(db, caller.user, session_id)
    attempt = submit(db, session)
    db.commit()
    return AttemptOut(
        session_id=session.id,
        attempt=attempt.number,
        submitted_at=attempt.submitted_at,
        late=attempt.late,
        status=session.status,
    )
