"""Lab report routes: the student's PDF, the teacher's copy of a student's and the
class's zip (built in the background: start, progress, download); the discussion the
student writes for it."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Form, Path, Query, Request
from fastapi.responses import JSONResponse, Response

from app.accounts.deps import CsrfProtected, CurrentUser
from app.core.exceptions import UserError
from app.lab.deps import OwnedSession, OwnSessionId
from app.lab.service import own_session
from app.models import DISCUSSION_MAX
from app.reports.class_zip import find_job, job_state, start_class_zip
from app.reports.discussion import save_discussion
from app.reports.service import report_response
from app.review.deps import ReviewableSession, TeacherAssignment
from app.web.deps import RowWriteSession, SessionDep
from app.web.exports import attachment
from app.web.i18n import translator
from app.web.render import flash, redirect, render, request_language

router = APIRouter(tags=["pages: reports"], include_in_schema=False)

AttemptNumber = Annotated[int | None, Query(ge=1, le=10_000)]
JobId = Annotated[int, Path(ge=1, le=2**31 - 1)]


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


ZIP_BASE = "/courses/{course_id}/assignments/{assignment_id}/reports"


@router.post(ZIP_BASE, dependencies=[CsrfProtected])
def build_class_reports(
    request: Request, target: TeacherAssignment, user: CurrentUser, db: SessionDep
):
    """Start (or join) the background build of the class's reports zip; its page follows."""
    job_id = start_class_zip(db, target.assignment, user, request_language(request))
    return redirect(f"{_zip_base(target)}/{job_id}")


@router.get(ZIP_BASE + "/{job_id}")
def class_reports_progress(
    request: Request, target: TeacherAssignment, db: SessionDep, job_id: JobId
):
    """The build's progress (a page, or JSON for the page's script), then its download."""
    job = find_job(db, target.assignment, job_id)
    if job is None:
        raise UserError("report.zip_not_found", status=404)
    state = job_state(job)
    if "application/json" in request.headers.get("accept", ""):
        return JSONResponse(
            {"state": state, "done": job.done, "total": job.total},
            headers={"Cache-Control": "no-store"},
        )
    context = {"course": target.course, "assignment": target.assignment, "job": job}
    return render(request, "reports/class_zip.html", {**context, "state": state})


@router.get(ZIP_BASE + "/{job_id}/download")
def class_reports_download(
    request: Request, target: TeacherAssignment, db: SessionDep, job_id: JobId
):
    job = find_job(db, target.assignment, job_id)
    if job is None or job_state(job) != "done" or job.content is None:
        raise UserError("report.zip_not_found", status=404)
    word = translator(job.language)("report.zip_name")
    name = attachment([target.course.name, target.assignment.title, word], "zip")
    return Response(
        job.content,
        media_type="application/zip",
        headers={"Content-Disposition": name, "Cache-Control": "no-store"},
    )


def _zip_base(target) -> str:
    return ZIP_BASE.format(course_id=target.course.id, assignment_id=target.assignment.id)


@router.post("/lab/sessions/{session_id}/discussion", dependencies=[CsrfProtected, RowWriteSession])
def save_discussion_page(
    request: Request,
    session_id: OwnSessionId,
    user: CurrentUser,
    db: SessionDep,
    discussion: Annotated[str, Form(max_length=DISCUSSION_MAX * 2)] = "",
):
    session = own_session(db, user, session_id)
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
