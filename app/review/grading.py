"""The grading desk: a review (feedback, position comments, points, rubric, letter) belongs
to the attempt it was written on; returning, releasing (one or many, each queuing its LMS
grade) and the teacher's next/previous student.  Reading attempts: ``app.lab.attempts``;
due dates and extensions: ``app.courses.deadlines``."""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass

from sqlmodel import Session, col, select

from app.core.exceptions import UserError
from app.core.typed_numbers import parse_typed_number
from app.lab.attempts import latest_attempt, rubric_of
from app.models import (
    Assignment,
    Attempt,
    GradeAmendment,
    LabSession,
    SessionStatus,
    User,
    utcnow,
)
from app.review.lms_outbox import queue_release

MAX_FEEDBACK = 20_000
MAX_COMMENT = 2_000
COMMENT_KEY = re.compile(r"comment-(heading|latitude)-[1-8]")


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
    try:  # as people type it: "87,5", "−1", a Chinese input method's "８７．５"
        value = parse_typed_number(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value) or not low <= value <= high:
        raise UserError(
            "review.bad_points",
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


def return_for_revision(db: Session, session: LabSession, attempt: Attempt) -> None:
    """Back to the student with the feedback (the student is notified: ``seen_at`` reset);
    the next attempt starts a fresh review.  The caller commits."""
    if session.status not in (SessionStatus.submitted, SessionStatus.returned):
        raise UserError("review.cannot_return", status=409)
    attempt.returned_at = utcnow()
    attempt.seen_at = None
    session.status = SessionStatus.returned
    session.updated_at = utcnow()
    db.add(attempt)
    db.add(session)


def release(db: Session, session: LabSession, attempt: Attempt) -> int:
    """Release the attempt's grade and feedback: the session is then graded (closed) and the
    grade queued for every LMS student of the session (``lms_outbox``); returns how many
    grade posts were queued (ring ``lms_outbox.wake_sender`` after the commit)."""
    if attempt.points is None:
        raise UserError("review.points_required")
    if session.status not in (SessionStatus.submitted, SessionStatus.returned):
        raise UserError("review.cannot_release", status=409)
    attempt.released_at = utcnow()
    attempt.seen_at = None
    session.status = SessionStatus.graded
    session.updated_at = utcnow()
    db.add(attempt)
    db.add(session)
    return queue_release(db, session, attempt)


MAX_REASON = 2_000


def amend(
    db: Session,
    session: LabSession,
    attempt: Attempt,
    review: Review,
    reason: str,
    teacher_id: int | None,
) -> int:
    """Change a released grade: the review is replaced, the change (what the grade was,
    who changed it, when and why) is kept as a :class:`GradeAmendment`, the student is
    notified again (``seen_at`` reset) and the new score is queued for every LMS student
    of the session; returns how many grade posts were queued.  The caller commits."""
    reason = reason.strip()[:MAX_REASON]
    if session.status != SessionStatus.graded or attempt.released_at is None:
        raise UserError("review.amend_not_released", status=409)
    if not reason:
        raise UserError("review.amend_reason_required", field="reason")
    if review.points is None:
        raise UserError("review.points_required")
    db.add(
        GradeAmendment(
            attempt_id=attempt.id,
            teacher_id=teacher_id,
            reason=reason,
            points_before=attempt.points,
            points_after=review.points,
            letter_before=attempt.letter,
            letter_after=review.letter,
            feedback_before=attempt.feedback,
        )
    )
    store_review(attempt, review)
    attempt.seen_at = None
    session.updated_at = utcnow()
    db.add(attempt)
    db.add(session)
    return queue_release(db, session, attempt)


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
        release(db, session, attempt)
        released += 1
    skipped += len(set(session_ids)) - len(sessions)
    return released, skipped


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
