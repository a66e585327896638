"""One operation shared by the student's page, the teacher's desk and the REST API: a
session's report as a PDF download; and the class's reports as one zip."""

from __future__ import annotations

import tempfile
import zipfile
from collections.abc import Iterator

from fastapi.responses import Response, StreamingResponse
from sqlmodel import Session

from app.db import read_session
from app.models import Assignment, Course, LabSession, User
from app.reports.content import Report, build_report
from app.reports.pdf import report_pdf
from app.reports.pdf_cache import content_key, pdf_cache
from app.review.service import class_rows
from app.web.exports import attachment, safe_name
from app.web.work_slots import pool

ZIP_BLOCK = 64 * 1024


def report_response(
    db: Session, session: LabSession, attempt: int | None, language: str, requester_id: int
) -> Response:
    """``session``'s report (attempt ``attempt``, or the current data) as a PDF download
    named after the session's owner, title and attempt: from the PDF cache when nothing
    it shows has changed, else rendered in one of the process's render slots, one at a
    time per requester (:mod:`app.web.work_slots`)."""
    content = cached_pdf(build_report(db, session, attempt), language, requester_id)
    owner = db.get(User, session.owner_id)
    version = f"attempt-{attempt}" if attempt is not None else "current"
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
    shared session once, named after the first of its members in the class list (the
    report itself names them all)."""
    seen: dict[int, tuple[str, int, int]] = {}
    for row in class_rows(db, assignment):
        if row.session is None or not row.attempts or row.session.id in seen:
            continue
        stem = safe_name(row.student.username)
        seen[row.session.id] = (stem, row.session.id, row.attempts[-1].number)
    return sorted(seen.values())


def class_reports(
    work: list[tuple[str, int, int]], language: str, requester_id: int
) -> Iterator[bytes]:
    """A zip of ``<username>_attempt-<n>.pdf`` reports, rendered one by one into a
    temporary file (its own database session: the download outlives the request's), then
    sent in blocks.  The requester's render slot, taken before the response starts, is
    held until the last report is rendered."""
    try:
        yield from _zipped(work, language)
    finally:
        pool("reports").give_back(requester_id)


def _zipped(work: list[tuple[str, int, int]], language: str) -> Iterator[bytes]:
    with tempfile.SpooledTemporaryFile(max_size=16 * 1024 * 1024) as spool:
        with read_session() as db, zipfile.ZipFile(spool, "w", zipfile.ZIP_STORED) as archive:
            for stem, session_id, number in work:  # PDFs are compressed already
                report = build_report(db, db.get(LabSession, session_id), number)
                archive.writestr(f"{stem}_attempt-{number}.pdf", cached_pdf(report, language, None))
        spool.seek(0)
        while block := spool.read(ZIP_BLOCK):
            yield block


def class_reports_response(
    db: Session,
    assignment: Assignment,
    course: Course,
    language: str,
    reports_word: str,
    requester_id: int,
) -> StreamingResponse:
    work = submitted_sessions(db, assignment)
    pool("reports").take(requester_id)  # refused now, with a page, not mid-download
    return StreamingResponse(
        class_reports(work, language, requester_id),
        media_type="application/zip",
        headers={
            "Content-Disposition": attachment([course.name, assignment.title, reports_word], "zip")
        },
    )
