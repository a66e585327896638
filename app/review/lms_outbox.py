"""Grades released for an LMS: the outbox and its doorbell.

Releasing an attempt (``app.review.grading.release``) queues one grade post per LMS student
of the session, in the same transaction; ``app.lti.grades`` drains the queue (its sender
waits on ``sender_doorbell``, which ``wake_sender`` rings after the release commits) and
retries what the platform refused.  The teacher's view of the queue: ``passback_state``.
"""

from __future__ import annotations

import asyncio
from dataclasses import dataclass
from datetime import datetime

from sqlalchemy import func
from sqlmodel import Session, col, select

from app.db import (
    read_session,
)
from app.models import (
    Assignment,
    Attempt,
    ExternalIdentity,
    LabSession,
    LtiGradePost,
    LtiPlatform,
    LtiResourceLink,
    SessionMember,
)

MAX_COMMENT = 4000


def queue_release(db: Session, session: LabSession, attempt: Attempt) -> int:
    """Queue the released ``attempt``'s grade for every LMS student of ``session`` whose
    assignment is placed in an LMS; returns how many posts were queued."""
    if session.assignment_id is None or attempt.points is None:
        return 0
    links = db.exec(
        select(LtiResourceLink).where(LtiResourceLink.assignment_id == session.assignment_id)
    ).all()
    if not links:
        return 0
    assignment = db.get(Assignment, session.assignment_id)
    members = {session.owner_id} | set(
        db.exec(select(SessionMember.user_id).where(SessionMember.session_id == session.id))
    )
    queued = 0
    for link in links:
        platform = db.get(LtiPlatform, link.platform_id)
        known = set(
            db.exec(
                select(ExternalIdentity.user_id).where(
                    ExternalIdentity.issuer == platform.issuer,
                    col(ExternalIdentity.user_id).in_(members),
                )
            )
        )
        for student_id in sorted(known):
            db.add(
                LtiGradePost(
                    attempt_id=attempt.id,
                    student_id=student_id,
                    link_id=link.id,
                    score=float(attempt.points),
                    maximum=float(assignment.max_points),
                    comment=(attempt.feedback or "")[:MAX_COMMENT],
                )
            )
            queued += 1
    return queued


@dataclass
class PassbackState:
    """What the teacher sees of an assignment's grade posts."""

    placed: bool  # the assignment is placed in an LMS
    sent: int = 0
    waiting: int = 0
    last_error: str | None = None
    next_try_at: datetime | None = None


def passback_state(db: Session, assignment_id: int) -> PassbackState:
    placed = db.exec(
        select(LtiResourceLink.id).where(LtiResourceLink.assignment_id == assignment_id)
    ).first()
    if placed is None:
        return PassbackState(False)
    rows = db.exec(
        select(LtiGradePost.status, func.count(LtiGradePost.id))
        .join(LtiResourceLink, col(LtiResourceLink.id) == LtiGradePost.link_id)
        .where(LtiResourceLink.assignment_id == assignment_id)
        .group_by(LtiGradePost.status)
    ).all()
    counts = dict(rows)
    failing = db.exec(
        select(LtiGradePost)
        .join(LtiResourceLink, col(LtiResourceLink.id) == LtiGradePost.link_id)
        .where(
            LtiResourceLink.assignment_id == assignment_id,
            LtiGradePost.status == "pending",
            col(LtiGradePost.last_error).is_not(None),
        )
        .order_by(col(LtiGradePost.next_try_at))
    ).first()
    return PassbackState(
        True,
        sent=counts.get("sent", 0),
        waiting=counts.get("pending", 0),
        last_error=failing.last_error if failing else None,
        next_try_at=failing.next_try_at if failing else None,
    )


def anything_queued() -> bool:
    with read_session() as db:
        return (
            db.exec(
                select(LtiGradePost.id).where(LtiGradePost.status == "pending").limit(1)
            ).first()
            is not None
        )


_waker: tuple[asyncio.AbstractEventLoop, asyncio.Event] | None = None


def sender_doorbell() -> asyncio.Event:
    """The event this worker's grade sender waits on (called from the sender's loop)."""
    global _waker
    event = asyncio.Event()
    _waker = (asyncio.get_running_loop(), event)
    return event


def wake_sender() -> None:
    """Ask this worker's sender to look now (after a release; callable from any thread).
    The sender works outside the request, so the release's transaction has ended."""
    if _waker is not None:
        loop, event = _waker
        loop.call_soon_threadsafe(event.set)
