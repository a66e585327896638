"""Submitting a session: its current data and results frozen as an attempt, under the
assignment's rules (attempts, due date)."""

from __future__ import annotations

import json

from sqlalchemy import update
from sqlmodel import Session

from app import __version__
from app.core.exceptions import UserError
from app.core.jsonsafe import json_safe
from app.courses.deadlines import due_for
from app.lab.attempts import attempts_of
from app.lab.copy_index import index_attempt
from app.lab.result_cache import cached_results
from app.lab.results import results_json
from app.lab.store import check_editable, current_takes
from app.models import (
    Assignment,
    Attempt,
    LabSession,
    LatePolicy,
    SessionStatus,
    Take,
    utcnow,
)


def submit(db: Session, session: LabSession) -> Attempt:
    """Freeze the current data and results as a new attempt.

    An assignment's rules apply: no new attempt while the last one awaits review or after
    grading, at most ``max_attempts``, and after the due date either refused or flagged late.
    """
    assignment = db.get(Assignment, session.assignment_id) if session.assignment_id else None
    previous = attempts_of(db, session.id)
    check_editable(session)
    if (
        assignment is not None
        and assignment.max_attempts
        and len(previous) >= assignment.max_attempts
    ):
        raise UserError(
            "lab.no_attempts_left",
            status=409,
            limit=assignment.max_attempts,
        )
    now = utcnow()
    due = due_for(db, assignment, session.owner_id)
    late = bool(due and now > due)
    if late and assignment.late_policy == LatePolicy.refuse:
        raise UserError("lab.past_due", status=409)
    takes = current_takes(db, session.id)
    results = cached_results(db, session, assignment, takes=takes).parts
    if all(outcome.result is None for outcome in results.values()):
        raise UserError("lab.nothing_to_submit")
    # an attempt's takes never change again (appends copy them): one statement for all
    db.exec(update(Take).where(Take.id.in_([take.id for take in takes])).values(frozen=True))
    attempt = Attempt(
        session_id=session.id,
        number=len(previous) + 1,
        take_ids=",".join(str(t.id) for t in takes),
        results_json=json.dumps(json_safe(results_json(results))),
        submitted_at=now,
        late=late,
        discussion=session.discussion,
        copy_indexed=True,  # its copy keys are added below, in this same transaction
    )
    session.status = SessionStatus.submitted
    session.updated_at = utcnow()
    db.add(attempt)
    db.add(session)
    db.flush()  # the attempt's id, for its copy keys
    index_attempt(db, attempt, takes)
    return attempt


def export_metadata(session: LabSession) -> dict:
    """What a teacher or a script needs to know about a session (never the secret truth)."""
    return {
        "software": f"GyroLab {__version__}",
        "session_id": session.id,
        "title": session.title,
        "assignment_id": session.assignment_id,
        "station": {
            "latitude_deg": session.latitude_deg,
            "earth_rate_deg_h": session.earth_rate_deg_h,
        },
        "heading": {
            "rotation": session.heading_rotation,
            "start_angle_deg": session.heading_start_deg,
        },
        "latitude": {
            "start_angle_deg": session.latitude_start_deg,
            "step_deg": session.latitude_step_deg,
        },
        "simulator_preset": session.simulator_preset,
        "status": session.status,
        "exported_at": utcnow().isoformat(),
    }
