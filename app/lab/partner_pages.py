"""Lab partners' pages: the group card's data, joining with a code, leaving, and the
state a partner's open page polls to follow the session live."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Form, Request
from sqlmodel import Session

from app.accounts.deps import CsrfProtected, CurrentUser
from app.core.exceptions import UserError
from app.lab import partners
from app.lab.deps import OwnedSession, OwnSessionId
from app.lab.service import own_session
from app.models import LabSession, User
from app.web.deps import RowWriteSession, SessionDep
from app.web.render import flash, redirect

router = APIRouter(prefix="/lab", tags=["pages: lab"], include_in_schema=False)


def partner_view(db: Session, session: LabSession, assignment, user: User) -> dict:
    """The lab-partners card: who is in the group, the code to join, whether one may leave."""
    members = partners.members_of(db, session)
    allows = assignment is not None and assignment.group_size > 1
    return {
        "members": members,
        "group_allowed": allows,
        "group_size": assignment.group_size if allows else 1,
        "is_owner": session.owner_id == user.id,
        "can_leave": session.owner_id != user.id and not partners.has_recordings(db, session.id),
    }


@router.get("/sessions/{session_id}/state")
def session_state(session: OwnedSession):
    """What a partner's open page polls: reload when the version changes."""
    return {
        "version": session.updated_at.isoformat(),
        "status": session.status,
        "recording": {"part": session.stream_part, "position": session.stream_position}
        if session.stream_part
        else None,
    }


@router.post("/join-group", dependencies=[CsrfProtected])
def join_group(
    request: Request,
    user: CurrentUser,
    db: SessionDep,
    code: Annotated[str, Form(max_length=32)] = "",
):
    """Join a classmate's session with the partner code they show."""
    try:
        session = partners.join(db, user, code)
    except UserError as problem:
        db.rollback()
        response = redirect("/lab#join-group")
        flash(response, request, problem.key, "error", **problem.params)
        return response
    db.commit()
    response = redirect(f"/lab/sessions/{session.id}")
    flash(response, request, "partners.joined", "success")
    return response


@router.post("/sessions/{session_id}/leave", dependencies=[CsrfProtected, RowWriteSession])
def leave_group(request: Request, session_id: OwnSessionId, user: CurrentUser, db: SessionDep):
    """A partner leaves the group (only before recording starts)."""
    session = own_session(db, user, session_id)
    try:
        partners.leave(db, user, session)
    except UserError as problem:
        db.rollback()
        response = redirect(f"/lab/sessions/{session.id}")
        flash(response, request, problem.key, "error", **problem.params)
        return response
    db.commit()
    response = redirect("/lab")
    flash(response, request, "partners.left", "success")
    return response
