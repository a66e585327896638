"""Assignment and Grade Services: released grades posted to the LMS, never lost.

Releasing a grade (one review or a bulk release) queues one ``LtiGradePost`` per student
of the session who came from the LMS, in the same transaction as the release.  A sender
then posts each as an AGS score (``scoreGiven`` of ``scoreMaximum``, the teacher's
feedback as the comment, ``FullyGraded``) to the resource link's line item -- found or
made by the assignment's ``resourceId`` when the link came without one.  A post stays
queued until the platform acknowledges it: a failure is recorded (``last_error``, shown
to the teacher) and retried after 30 s, 1, 2, 4 … minutes, at most hourly.  Senders:
a loop in every worker (``run_sender``), woken right after a release, "Send now" on the
assignment page and ``gyrolab lti send-grades``.  A post is claimed by moving its next
try forward before the network call, so two workers never send it at once.
"""

from __future__ import annotations

import asyncio
import logging
from contextlib import suppress
from dataclasses import dataclass
from datetime import datetime, timedelta

import requests
from pylti1p3.assignments_grades import AssignmentsGradesService
from pylti1p3.exception import LtiException
from pylti1p3.grade import Grade
from pylti1p3.lineitem import LineItem
from sqlalchemy import update
from sqlalchemy.exc import DBAPIError
from sqlmodel import Session, col, select
from starlette.concurrency import run_in_threadpool

from app.db import (
    database_busy,
    get_engine,
    read_session,
    statement_session,
    storage_unavailable,
    write_session,
)
from app.lti.handshake import old_values_removed, service_connector
from app.lti.keys import ensure_key
from app.lti.platforms import registration_of
from app.models import (
    Assignment,
    Attempt,
    ExternalIdentity,
    LtiContext,
    LtiGradePost,
    LtiPlatform,
    LtiResourceLink,
    utcnow,
)
from app.review.lms_outbox import anything_queued, sender_doorbell
from app.web.errors import report_storage_fault

log = logging.getLogger("gyrolab.lti")
SCORE_SCOPES = [
    "https://purl.imsglobal.org/spec/lti-ags/scope/lineitem",
    "https://purl.imsglobal.org/spec/lti-ags/scope/lineitem.readonly",
    "https://purl.imsglobal.org/spec/lti-ags/scope/score",
]
FIRST_PAUSE_S = 30
LONGEST_PAUSE_S = 3600
CLAIM_S = 300  # a claimed post is retried after this if its sender died
SENDER_PERIOD_S = 60
BATCH = 200


def line_item(assignment_id: int | None, title: str, maximum: float) -> LineItem:
    """An assignment's AGS line item: found again by its ``resourceId``."""
    return (
        LineItem()
        .set_score_maximum(maximum)
        .set_label(title)
        .set_resource_id(f"gyrolab-assignment-{assignment_id}")
        .set_tag("gyrolab")
    )


def pause_after(tries: int) -> timedelta:
    """30 s, 60 s, 2 min, 4 min … at most an hour, after the ``tries``-th failure."""
    return timedelta(seconds=min(FIRST_PAUSE_S * 2 ** max(tries - 1, 0), LONGEST_PAUSE_S))


def _claim(post_id: int, now: datetime) -> bool:
    with statement_session() as db:
        result = db.exec(
            update(LtiGradePost)
            .where(
                LtiGradePost.id == post_id,
                LtiGradePost.status == "pending",
                col(LtiGradePost.next_try_at) <= now,
            )
            .values(next_try_at=now + timedelta(seconds=CLAIM_S))
        )
        db.commit()
        return result.rowcount == 1


@dataclass
class Outbound:
    """Everything one post needs, read before the network call."""

    post_id: int
    tries: int
    registration: object
    lineitems_url: str | None
    lineitem_url: str | None
    scopes: list[str]
    grade: Grade
    line_item: LineItem


def _outbound(db: Session, post: LtiGradePost) -> Outbound:
    link = db.get(LtiResourceLink, post.link_id)
    context = db.get(LtiContext, link.context_row_id)
    platform = db.get(LtiPlatform, link.platform_id)
    assignment = db.get(Assignment, link.assignment_id) if link.assignment_id else None
    attempt = db.get(Attempt, post.attempt_id)
    subject = db.exec(
        select(ExternalIdentity.subject).where(
            ExternalIdentity.user_id == post.student_id,
            ExternalIdentity.issuer == platform.issuer,
        )
    ).first()
    when = attempt.released_at if attempt and attempt.released_at else post.created_at
    grade = (
        Grade()
        .set_score_given(post.score)
        .set_score_maximum(post.maximum)
        .set_activity_progress("Completed")
        .set_grading_progress("FullyGraded")
        .set_timestamp(when.isoformat(timespec="milliseconds").replace("+00:00", "Z"))
        .set_user_id(subject or "")
    )
    if post.comment:
        grade.set_comment(post.comment)
    item = line_item(
        link.assignment_id, assignment.title if assignment else "GyroLab", post.maximum
    ).set_resource_link_id(link.resource_link_id)
    scopes = context.ags_scopes.split() or SCORE_SCOPES
    return Outbound(
        post.id,
        post.tries,
        registration_of(db, platform),
        context.lineitems_url,
        link.lineitem_url,
        scopes,
        grade,
        item,
    )


def _post(item: Outbound) -> str | None:
    """Send one score; the line item URL used (to remember it for the link)."""
    data = {"scope": item.scopes, "lineitems": item.lineitems_url or ""}
    if item.lineitem_url:
        data["lineitem"] = item.lineitem_url
    service = AssignmentsGradesService(service_connector(item.registration), data)
    if item.lineitem_url:
        service.put_grade(item.grade)
        return item.lineitem_url
    if not item.lineitems_url:
        raise LtiException("The LMS gave no line item and no line items service.")
    found = service.find_or_create_lineitem(item.line_item, find_by="resource_id")
    service.put_grade(item.grade, found)
    return found.get_id()


def send_due(now: datetime | None = None, only: list[int] | None = None) -> dict[str, int]:
    """Send every post whose time has come (or the posts ``only``); counts sent/failed."""
    now = now or utcnow()
    statement = (
        select(LtiGradePost.id)
        .where(LtiGradePost.status == "pending", col(LtiGradePost.next_try_at) <= now)
        .order_by(LtiGradePost.id)
        .limit(BATCH)
    )
    if only is not None:
        statement = statement.where(col(LtiGradePost.id).in_(only))
    with read_session() as db:
        due = list(db.exec(statement))
    counts = {"sent": 0, "failed": 0}
    for post_id in due:
        if not _claim(post_id, now):
            continue  # another sender has it
        ensure_key()
        with read_session() as db:
            item = _outbound(db, db.get(LtiGradePost, post_id))
        try:
            used_lineitem = _post(item)
        except (LtiException, requests.RequestException, ValueError, KeyError) as error:
            _failed(item, error)
            counts["failed"] += 1
        else:
            _sent(item, used_lineitem)
            counts["sent"] += 1
    return counts


def _sent(item: Outbound, lineitem_url: str | None) -> None:
    with write_session() as db:
        post = db.get(LtiGradePost, item.post_id)
        post.status, post.sent_at, post.last_error = "sent", utcnow(), None
        post.tries += 1
        db.add(post)
        link = db.get(LtiResourceLink, post.link_id)
        if lineitem_url and not link.lineitem_url:
            link.lineitem_url = lineitem_url[:1000]
            db.add(link)


def _failed(item: Outbound, error: Exception) -> None:
    response = getattr(error, "response", None)
    detail = str(error) or type(error).__name__
    if response is not None:
        detail = f"{detail} (HTTP {response.status_code})"
    log.warning("grade post %s failed: %s", item.post_id, detail)
    with write_session() as db:
        post = db.get(LtiGradePost, item.post_id)
        post.tries += 1
        post.last_error = detail[:500]
        post.next_try_at = utcnow() + pause_after(post.tries)
        db.add(post)


def send_now(assignment_id: int) -> dict[str, int]:
    """The teacher's "Send now": every waiting post of the assignment, at once."""
    with write_session() as db:
        ids = list(
            db.exec(
                select(LtiGradePost.id)
                .join(LtiResourceLink, col(LtiResourceLink.id) == LtiGradePost.link_id)
                .where(
                    LtiResourceLink.assignment_id == assignment_id,
                    LtiGradePost.status == "pending",
                )
            )
        )
        if ids:
            db.exec(
                update(LtiGradePost)
                .where(col(LtiGradePost.id).in_(ids))
                .values(next_try_at=utcnow())
            )
    return send_due(only=ids) if ids else {"sent": 0, "failed": 0}


async def run_sender(period_s: float = SENDER_PERIOD_S) -> None:
    """The worker's loop: send what is due every ``period_s`` or when woken, and tidy the
    handshake values."""
    event = sender_doorbell()
    while True:
        with suppress(TimeoutError):
            await asyncio.wait_for(event.wait(), period_s)
        event.clear()
        try:
            if await run_in_threadpool(anything_queued):
                await run_in_threadpool(send_due)
            await run_in_threadpool(old_values_removed)
        except DBAPIError as error:  # a full or read-only disk: said as requests say it
            if storage_unavailable(error):
                report_storage_fault(error)
                get_engine().dispose()
            elif database_busy(error):
                log.info("LTI grade sender: database busy, next round")
            else:
                log.exception("LTI grade sender")
        except Exception:  # noqa: BLE001 -- the loop must outlive a bad moment
            log.exception("LTI grade sender")
