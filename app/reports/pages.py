"""Lab report routes: the student's PDF, the teacher's copy of a student's and the
class's zip; the discussion the student writes for it."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Form, Query, Request

from app.core.exceptions import UserError
from app.lab.deps import OwnedSession
from app.models import DISCUSSION_MAX
from app.reports.discussion import save_discussion
from app.reports.service import class_reports_response, report_response
from app.review.deps import ReviewableSession, TeacherAssignment
from app.web.deps import CsrfProtected, CurrentUser, SessionDep
from app.web.i18n import translator
from app.web.render import flash, redirect, request_language

router = APIRouter(tags=["pages: reports"], include_in_schema=False)

AttemptNumber = Annotated[int | None, Query(ge=1, le=10_000)]


@router.get("/lab/sessions/{session_id}/report.pdf")
def student_report(
    request: Request,
    session: OwnedSession,
    user: CurrentUser,
    db: SessionDep,
    attempt: AttemptNumber = None,
):
    return report_response(db, session, attempt, request_language(request), user.id)


@router.get("/review/sessions/{session_id}/report.pdf")
def teacher_report(
    request: Request,
    target: ReviewableSession,
    user: CurrentUser,
    db: SessionDep,
    attempt: AttemptNumber = None,
):
    return report_response(db, target.session, attempt, request_language(request), user.id)


@router.get("/courses/{course_id}/assignments/{assignment_id}/reports.zip")
def class_reports(request: Request, target: TeacherAssignment, user: CurrentUser, db: SessionDep):
    language = request_language(request)
    word = translator(language)("report.zip_name")
    return class_reports_response(db, target.assignment, target.course, language, word, user.id)


@router.post("/lab/sessions/{session_id}/discussion", dependencies=[CsrfProtected])
def save_discussion_page(
    request: Request,
    session: OwnedSession,
    db: SessionDep,
    discussion: Annotated[str, Form(max_length=DISCUSSION_MAX * 2)] = "",
):
    response = redirect(f"/lab/sessions/{session.id}#discussion")
    try:
        save_discussion(db, session, discussion)
    except UserError as error:
        db.rollback()
        flash(response, request, error.key, "error", **error.params)
        return response
    db.commit()
    flash(response, request, "report.discussion_saved")
    return response
