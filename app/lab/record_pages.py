"""The student lab's actions on a session: record positions typed in the grid, turn the
virtual table, choose the order, read results, submit and download.  Each calls the lab
service.  A file's readings: :mod:`app.lab.file_pages`."""

from __future__ import annotations

import json
from datetime import datetime
from typing import Annotated

import numpy as np
from fastapi import APIRouter, Body, Form, Request
from fastapi.responses import Response, StreamingResponse

from app.accounts.deps import CsrfProtected, CurrentUser
from app.core.exceptions import UserError
from app.core.jsonsafe import json_safe
from app.lab.deps import OwnedSession, OwnSessionId
from app.lab.exports import Selection, readings_csv, session_json
from app.lab.grid import grid_readings
from app.lab.result_cache import results_of
from app.lab.schemas import ManualReadings, Plane, Trim, Turn
from app.lab.service import own_session, record_positions, recordable_session
from app.lab.sim import nominal_angle, wait_for_gyro, warm_up_state
from app.lab.store import check_position, set_symmetric_order
from app.lab.submissions import submit
from app.lab.trim import trim_position
from app.models import InputMethod, LabSession, Part
from app.web.deps import RowWriteSession, SessionDep
from app.web.exports import attachment
from app.web.render import flash, redirect
from app.web.work_slots import held_while_streaming

router = APIRouter(prefix="/lab", tags=["pages: lab"], include_in_schema=False)
# A route that changes a session reads it in its handler, after ``OwnSessionId`` checked
# it is the caller's (lab.deps: why).


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
