"""Reading submitted attempts as their student sees them: the rubric, the latest attempt,
its comments and rubric scores, the grade once released, and the notices of reviews not
yet opened (``mark_seen`` when the student opens their work)."""

from __future__ import annotations

import json
from dataclasses import dataclass

from sqlalchemy import bindparam
from sqlmodel import Session, col, select

from app.lab.partners import in_sessions_of
from app.models import (
    Assignment,
    Attempt,
    GradeAmendment,
    LabSession,
    SessionStatus,
    User,
    utcnow,
)

# a session's attempts in order (its page, a submit), built once
ATTEMPTS_OF_SESSION = (
    select(Attempt).where(Attempt.session_id == bindparam("session_id")).order_by(Attempt.number)
)


def attempts_of(db: Session, session_id: int) -> list[Attempt]:
    """The session's attempts, first to last."""
    return list(db.exec(ATTEMPTS_OF_SESSION, params={"session_id": session_id}).all())


def rubric_of(assignment: Assignment | None) -> list[dict]:
    """The assignment's rubric: ``[{"name": str, "points": float}, ...]`` (may be empty)."""
    if assignment is None:
        return []
    try:
        rubric = json.loads(assignment.rubric or "[]")
    except ValueError:
        return []
    return [item for item in rubric if isinstance(item, dict) and "name" in item]


def latest_attempt(db: Session, session_id: int) -> Attempt | None:
    return db.exec(
        select(Attempt).where(Attempt.session_id == session_id).order_by(col(Attempt.number).desc())
    ).first()


def comments_of(attempt: Attempt | None) -> dict[str, str]:
    """An attempt's position comments, ``{"heading-1": "..."}``."""
    if attempt is None:
        return {}
    try:
        comments = json.loads(attempt.feedback_positions or "{}")
    except ValueError:
        return {}
    return {str(k): str(v) for k, v in comments.items()} if isinstance(comments, dict) else {}


def rubric_scores_of(attempt: Attempt | None) -> dict[str, float]:
    if attempt is None:
        return {}
    try:
        scores = json.loads(attempt.rubric_points or "{}")
    except ValueError:
        return {}
    return {str(k): float(v) for k, v in scores.items()} if isinstance(scores, dict) else {}


def grade_text(attempt: Attempt | None, assignment: Assignment | None) -> str:
    """ "85 / 100 (B+)", "85 / 100", "B+" or "" for an attempt's grade."""
    if attempt is None:
        return ""
    parts = []
    if attempt.points is not None:
        maximum = assignment.max_points if assignment is not None else None
        parts.append(f"{attempt.points:g}" + (f" / {maximum:g}" if maximum else ""))
    if attempt.letter:
        parts.append(f"({attempt.letter})" if parts else attempt.letter)
    return " ".join(parts)


def released_grade(session: LabSession, attempts: list[Attempt], assignment) -> str:
    """The grade a student may see: the released attempt's, once the session is graded."""
    if session.status != SessionStatus.graded or not attempts:
        return ""
    return grade_text(attempts[-1], assignment)


def amendments_of(db: Session, attempt: Attempt | None) -> list[GradeAmendment]:
    """The changes made to an attempt's released grade, oldest first."""
    if attempt is None:
        return []
    return list(
        db.exec(
            select(GradeAmendment)
            .where(GradeAmendment.attempt_id == attempt.id)
            .order_by(GradeAmendment.amended_at, GradeAmendment.id)
        ).all()
    )


def shown_to_student(attempt: Attempt) -> bool:
    """Has the teacher given this attempt's review to the student (returned or released)?"""
    return attempt.returned_at is not None or attempt.released_at is not None


@dataclass
class Notice:
    session_id: int
    title: str
    kind: str  # "released" | "returned"
    number: int
    grade: str


def notices(db: Session, student: User) -> list[Notice]:
    """Reviews given to the student that they have not opened yet, newest first."""
    rows = db.exec(
        select(Attempt, LabSession, Assignment)
        .join(LabSession, LabSession.id == Attempt.session_id)
        .join(Assignment, Assignment.id == LabSession.assignment_id)
        .where(
            in_sessions_of(student.id),
            col(Attempt.seen_at).is_(None),
            (col(Attempt.released_at).is_not(None)) | (col(Attempt.returned_at).is_not(None)),
        )
        .order_by(col(Attempt.submitted_at).desc())
    ).all()
    out = []
    for attempt, session, assignment in rows:
        kind = "released" if attempt.released_at is not None else "returned"
        grade = grade_text(attempt, assignment) if kind == "released" else ""
        out.append(Notice(session.id, assignment.title, kind, attempt.number, grade))
    return out


def mark_seen(db: Session, attempts: list[Attempt]) -> bool:
    """The student opened their work: its given reviews are no longer news.  True if
    anything changed (the caller commits)."""
    changed = False
    for attempt in attempts:
        if shown_to_student(attempt) and attempt.seen_at is None:
            attempt.seen_at = utcnow()
            db.add(attempt)
            changed = True
    return changed
