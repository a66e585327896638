"""The grading desk: a review (feedback, position comments, points, rubric, letter) belongs
to the attempt it was written on; returning, releasing (one or many), extensions, the
student's notices and the teacher's next/previous student."""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass
from datetime import datetime

from sqlmodel import Session, col, select

from app.core.exceptions import UserError
from app.core.readings import parse_decimal
from app.lab.partners import in_sessions_of
from app.lti.grades import queue_release
from app.models import (
    Assignment,
    Attempt,
    Extension,
    LabSession,
    SessionStatus,
    User,
    utcnow,
)

MAX_FEEDBACK = 20_000
MAX_COMMENT = 2_000
COMMENT_KEY = re.compile(r"comment-(heading|latitude)-[1-8]")


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


@dataclass
class Review:
    """A teacher's review as typed: checked, not yet stored."""

    feedback: str
    comments: dict[str, str]
    points: float | None
    rubric_points: dict[str, float]
    letter: str | None


def _points(text: str, low: float, high: float, field: str) -> float | None:
    text = text.strip()
    if not text:
        return None
    if text.count(",") == 1 and "." not in text:
        text = text.replace(",", ".")  # a decimal comma: "87,5"
    try:
        value = parse_decimal(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value) or not low <= value <= high:
        raise UserError(
            "review.bad_points",
            f"{field}: enter a number from {low:g} to {high:g}.",
            field=field,
            low=f"{low:g}",
            high=f"{high:g}",
        )
    return value


def parse_review(form: dict[str, str], assignment: Assignment) -> Review:
    """The review form's fields → a :class:`Review`; wrong points raise a UserError.

    With a rubric, the points are the sum of the criteria's points (each within its own
    maximum); without one, the teacher types the points out of ``max_points``.
    """
    feedback = str(form.get("feedback", ""))[:MAX_FEEDBACK]
    comments = {
        key.removeprefix("comment-"): str(value).strip()[:MAX_COMMENT]
        for key, value in form.items()
        if COMMENT_KEY.fullmatch(key) and str(value).strip()
    }
    rubric = rubric_of(assignment)
    scores: dict[str, float] = {}
    for index, criterion in enumerate(rubric):
        value = _points(
            str(form.get(f"rubric-{index}", "")), 0.0, float(criterion["points"]), criterion["name"]
        )
        if value is not None:
            scores[str(index)] = value
    if rubric:
        points = sum(scores.values()) if len(scores) == len(rubric) else None
    else:
        points = _points(str(form.get("points", "")), 0.0, assignment.max_points, "points")
    letter = str(form.get("letter", "")).strip()[:32] or None
    return Review(feedback, comments, points, scores, letter)


def store_review(attempt: Attempt, review: Review) -> None:
    attempt.feedback = review.feedback
    attempt.feedback_positions = json.dumps(review.comments, ensure_ascii=False)
    attempt.points = review.points
    attempt.rubric_points = json.dumps(review.rubric_points)
    attempt.letter = review.letter


def return_for_revision(session: LabSession, attempt: Attempt) -> None:
    """Back to the student with the feedback; the next attempt starts a fresh review."""
    if session.status not in (SessionStatus.submitted, SessionStatus.returned):
        raise UserError("review.cannot_return", "Only submitted work can be returned.", status=409)
    attempt.returned_at = utcnow()
    attempt.seen_at = None
    session.status = SessionStatus.returned


def release(session: LabSession, attempt: Attempt) -> None:
    """Release the attempt's grade and feedback; the session is then graded (closed)."""
    if attempt.points is None:
        raise UserError("review.points_required", "Enter the points before releasing.")
    if session.status not in (SessionStatus.submitted, SessionStatus.returned):
        raise UserError("review.cannot_release", "Only submitted work can be released.", status=409)
    attempt.released_at = utcnow()
    attempt.seen_at = None
    session.status = SessionStatus.graded
    session.updated_at = utcnow()


def bulk_release(db: Session, assignment: Assignment, session_ids: list[int]) -> tuple[int, int]:
    """Release every chosen submitted session of ``assignment`` whose latest attempt has
    points: (released, skipped)."""
    released = skipped = 0
    if not session_ids:
        return 0, 0
    sessions = db.exec(
        select(LabSession).where(
            LabSession.assignment_id == assignment.id, col(LabSession.id).in_(session_ids)
        )
    ).all()
    for session in sessions:
        attempt = latest_attempt(db, session.id)
        if (
            attempt is None
            or attempt.points is None
            or session.status not in (SessionStatus.submitted, SessionStatus.returned)
        ):
            skipped += 1
            continue
        release(session, attempt)
        db.add(attempt)
        db.add(session)
        queue_release(db, session, attempt)
        released += 1
    skipped += len(set(session_ids)) - len(sessions)
    return released, skipped


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


def shown_to_student(attempt: Attempt) -> bool:
    """Has the teacher given this attempt's review to the student (returned or released)?"""
    return attempt.returned_at is not None or attempt.released_at is not None


def due_for(db: Session, assignment: Assignment | None, student_id: int) -> datetime | None:
    """The student's due date: their extension, else the assignment's."""
    if assignment is None:
        return None
    extension = db.exec(
        select(Extension).where(
            Extension.assignment_id == assignment.id, Extension.student_id == student_id
        )
    ).first()
    return extension.due_at if extension else assignment.due_at


def extensions_of(db: Session, assignment: Assignment) -> dict[int, datetime]:
    """``{student_id: due_at}`` for every extension of ``assignment`` (one query)."""
    rows = db.exec(select(Extension).where(Extension.assignment_id == assignment.id)).all()
    return {row.student_id: row.due_at for row in rows}


def set_extension(
    db: Session, assignment: Assignment, student_id: int, due_at: datetime | None
) -> None:
    """Give one student a later due date (None removes the extension)."""
    existing = db.exec(
        select(Extension).where(
            Extension.assignment_id == assignment.id, Extension.student_id == student_id
        )
    ).first()
    if due_at is None:
        if existing is not None:
            db.delete(existing)
        return
    if existing is None:
        existing = Extension(assignment_id=assignment.id, student_id=student_id, due_at=due_at)
    existing.due_at = due_at
    db.add(existing)


@dataclass
class Neighbours:
    previous: tuple[int, str] | None  # (session id, display name)
    next: tuple[int, str] | None
    index: int  # 1-based place among the sessions
    total: int


def neighbours(db: Session, session: LabSession) -> Neighbours:
    """The sessions before and after ``session`` in the dashboard's order (by username)."""
    rows = db.exec(
        select(LabSession.id, User.display_name)
        .join(User, User.id == LabSession.owner_id)
        .where(LabSession.assignment_id == session.assignment_id)
        .order_by(User.username)
    ).all()
    ids = [row[0] for row in rows]
    if session.id not in ids:
        return Neighbours(None, None, 0, len(ids))
    at = ids.index(session.id)
    previous = tuple(rows[at - 1]) if at > 0 else None
    following = tuple(rows[at + 1]) if at + 1 < len(rows) else None
    return Neighbours(previous, following, at + 1, len(ids))  # type: ignore[arg-type]


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
