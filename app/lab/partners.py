"""Lab partners: students at one bench share one session of an assignment that allows
groups.  The session's owner shows a partner code; a classmate enters it to join (their
consent); every member sees, records in and submits the one session and gets its grade.
A member may leave only before any recording is stored."""

from __future__ import annotations

import secrets

from sqlalchemy import bindparam
from sqlmodel import Session, col, func, select

from app.core.exceptions import UserError
from app.models import (
    JOIN_CODE_ALPHABET,
    Assignment,
    Attempt,
    Course,
    Enrollment,
    LabSession,
    SessionMember,
    Take,
    User,
)

MAX_GROUP = 3


def new_partner_code() -> str:
    """Six characters from the join-code alphabet (no 0/O/1/I): 30 bits, typed at a bench."""
    return "".join(secrets.choice(JOIN_CODE_ALPHABET) for _ in range(6))


def is_member(db: Session, session: LabSession, user: User) -> bool:
    """The session's owner or one of its partners."""
    if session.owner_id == user.id:
        return True
    return (
        db.exec(
            select(SessionMember.id).where(
                SessionMember.session_id == session.id, SessionMember.user_id == user.id
            )
        ).first()
        is not None
    )


def members_of(db: Session, session: LabSession) -> list[User]:
    """The owner first, then the partners in the order they joined."""
    owner = db.get(User, session.owner_id)
    partners = db.exec(PARTNERS, params={"session_id": session.id}).all()
    return [owner, *partners]


PARTNERS = (  # built once (a lab page's statement)
    select(User)
    .join(SessionMember, SessionMember.user_id == User.id)
    .where(SessionMember.session_id == bindparam("session_id"))
    .order_by(SessionMember.joined_at)
)


def in_sessions_of(user_id: int):
    """A condition on LabSession: the user's own sessions and those they joined as a
    partner (one clause for every list of "my sessions")."""
    joined = select(SessionMember.session_id).where(SessionMember.user_id == user_id)
    return (LabSession.owner_id == user_id) | col(LabSession.id).in_(joined)


def member_map(db: Session, assignment: Assignment) -> dict[int, LabSession]:
    """``{partner's user id: the session they joined}`` for an assignment (one query)."""
    rows = db.exec(
        select(SessionMember.user_id, LabSession)
        .join(LabSession, LabSession.id == SessionMember.session_id)
        .where(LabSession.assignment_id == assignment.id)
    ).all()
    return {user_id: session for user_id, session in rows}


def ensure_partner_code(db: Session, session: LabSession, assignment: Assignment | None) -> None:
    """Give an assignment session its partner code when the assignment allows groups."""
    if assignment is None or assignment.group_size <= 1 or session.partner_code:
        return
    session.partner_code = new_partner_code()
    db.add(session)


def has_recordings(db: Session, session_id: int) -> bool:
    return db.exec(select(Take.id).where(Take.session_id == session_id)).first() is not None


def join(db: Session, user: User, code: str) -> LabSession:
    """Join the session whose partner code is ``code``.  The caller commits.

    The classmate must be enrolled in the assignment's course, not yet in a group for it,
    and must not have recorded anything of their own for it (an empty session of theirs is
    removed).  The group may not be full nor already submitted.
    """
    code = code.strip().upper()
    session = (
        db.exec(select(LabSession).where(LabSession.partner_code == code)).first() if code else None
    )
    assignment = db.get(Assignment, session.assignment_id) if session else None
    if session is None or assignment is None or assignment.group_size <= 1:
        raise UserError("partners.no_such_code", status=404)
    enrolled = db.exec(
        select(Enrollment.id)
        .join(Course, Course.id == Enrollment.course_id)
        .where(Course.id == assignment.course_id, Enrollment.student_id == user.id)
    ).first()
    if enrolled is None:
        raise UserError("partners.no_such_code", status=404)
    if is_member(db, session, user):
        return session
    if member_map(db, assignment).get(user.id) is not None:
        raise UserError("partners.already_in_group", status=409)
    size = (
        1
        + db.exec(
            select(func.count())
            .select_from(SessionMember)
            .where(SessionMember.session_id == session.id)
        ).one()
    )
    if size >= min(assignment.group_size, MAX_GROUP):
        raise UserError("partners.full", limit=assignment.group_size, status=409)
    if db.exec(select(Attempt.id).where(Attempt.session_id == session.id)).first():
        raise UserError("partners.already_submitted", status=409)
    own = db.exec(
        select(LabSession).where(
            LabSession.assignment_id == assignment.id, LabSession.owner_id == user.id
        )
    ).first()
    if own is not None:
        if has_recordings(db, own.id):
            raise UserError("partners.has_own_work", status=409)
        db.delete(own)
    db.add(SessionMember(session_id=session.id, user_id=user.id))
    return session


def leave(db: Session, user: User, session: LabSession) -> None:
    """A partner leaves the group, only before any recording is stored.  The caller
    commits.  (The owner's session is theirs: they stay.)"""
    membership = db.exec(
        select(SessionMember).where(
            SessionMember.session_id == session.id, SessionMember.user_id == user.id
        )
    ).first()
    if membership is None:
        raise UserError("partners.owner_stays", status=409)
    if has_recordings(db, session.id):
        raise UserError("partners.recording_started", status=409)
    db.delete(membership)


def group_names(db: Session, session_ids: list[int]) -> dict[int, list[str]]:
    """``{session id: [display names of owner and partners]}`` for sessions with partners."""
    if not session_ids:
        return {}
    rows = db.exec(
        select(SessionMember.session_id, User.display_name)
        .join(User, User.id == SessionMember.user_id)
        .where(col(SessionMember.session_id).in_(session_ids))
        .order_by(SessionMember.joined_at)
    ).all()
    partners: dict[int, list[str]] = {}
    for session_id, name in rows:
        partners.setdefault(session_id, []).append(name)
    owners = dict(
        db.exec(
            select(LabSession.id, User.display_name)
            .join(User, User.id == LabSession.owner_id)
            .where(col(LabSession.id).in_(list(partners)))
        ).all()
    )
    return {sid: [owners[sid], *names] for sid, names in partners.items() if sid in owners}
