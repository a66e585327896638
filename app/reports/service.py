"""One operation shared by the student's page, the teacher's desk and the REST API: a
session's report as a PDF download (from the PDF cache when nothing it shows changed);
and the list of reports the class's zip holds (built by ``class_zip``)."""

from __future__ import annotations

from fastapi.responses import Response
from sqlmodel import Session

from app.models import Assignment, LabSession, User
from app.reports.content import Report, build_report
from app.reports.pdf import report_pdf
from app.reports.pdf_cache import content_key, pdf_cache
from app.review.service import class_rows
from app.web.exports import attachment, safe_name
from app.web.work_slots import pool


def report_response(
    db: Session, session: LabSession, attempt: int | None, language: str, requester_id: int
) -> Response:
    """``session``'s report (attempt ``attempt``, or the current data) as a PDF download
    named after the session's owner, title and attempt: from the PDF cache when nothing
    it shows has changed, else rendered in one of the process's render slots, one at a
    time per requester (:mod:`app.web.work_slots`)."""
    report = build_report(db, session, attempt)
    content = cached_pdf(report, language, requester_id)
    owner = db.get(User, session.owner_id)
    version = f"attempt-{report.attempt.number}" if report.attempt is not None else "current"
    return Response(
        content,
        media_type="application/pdf",
        headers={
            "Content-Disposition": attachment([owner.username, session.title, version], "pdf"),
            "Cache-Control": "no-store",
        },
    )


def cached_pdf(report: Report, language: str, requester_id: int | None) -> bytes:
    """The PDF of ``report``: the cached one for the same content, or rendered (in a
    render slot of ``requester_id``'s, unless the caller holds one already: None)."""
    cache = pdf_cache()
    key = content_key(report, language)
    if (content := cache.get(key)) is not None:
        return content
    if requester_id is None:
        content = report_pdf(report, language)
    else:
        with pool("reports").slot(requester_id):
            content = report_pdf(report, language)
    cache.put(key, content)
    return content


def submitted_sessions(db: Session, assignment: Assignment) -> list[tuple[str, int, int]]:
    """(file stem, session id, latest attempt number) of every submitted session; a group's
    shared session once, its stem naming every member in class-list order
    ("student1+student2"), so that the zip shows whose report each file is."""
    members: dict[int, list[str]] = {}
    latest: dict[int, int] = {}
    for row in class_rows(db, assignment):
        if row.session is None or not row.attempts:
            continue
        members.setdefault(row.session.id, []).append(safe_name(row.student.username))
        latest[row.session.id] = row.attempts[-1].number
    return sorted(("+".join(names), sid, latest[sid]) for sid, names in members.items())
