"""The class's reports as one zip, built in the background with its progress shown.

A teacher starts a build (``start_class_zip``): the zip is rendered report by report in a
thread of the worker that took the request, holding that teacher's render slot (so the
process's bound on renders holds, and a second build of theirs is refused at once); each
report comes from the PDF cache when nothing it shows has changed.  Progress and the
finished zip are kept in ``report_job``, so any worker can show the page and serve the
download.  A build of the same assignment and language that is under way is joined
rather than started twice; one that has not moved for ``STALLED`` (its worker stopped) is
shown as interrupted and may be started again.  Older zips of an assignment are deleted
when a newer one is done.
"""

from __future__ import annotations

import logging
import tempfile
import threading
import zipfile
from datetime import timedelta

from sqlalchemy import delete
from sqlmodel import Session, col, select

from app.db import read_session, write_session
from app.models import Assignment, LabSession, ReportJob, User, utcnow
from app.reports.content import build_report
from app.reports.service import cached_pdf, submitted_sessions
from app.web.work_slots import pool

STALLED = timedelta(minutes=10)
log = logging.getLogger("gyrolab.reports")


def job_state(job: ReportJob) -> str:
    """``running``, ``done``, ``failed`` -- or ``interrupted`` for a build whose worker
    stopped (no progress for ``STALLED``)."""
    if job.status == "running" and utcnow() - job.updated_at > STALLED:
        return "interrupted"
    return job.status


def start_class_zip(db: Session, assignment: Assignment, requester: User, language: str) -> int:
    """The id of the build of ``assignment``'s reports in ``language``: the one under way,
    or a new one started now (the requester's render slot taken first: 429/503 at once).
    ``db`` is the request's writing session; the new build is committed in it."""
    running = db.exec(
        select(ReportJob)
        .where(
            ReportJob.assignment_id == assignment.id,
            ReportJob.language == language,
            ReportJob.status == "running",
        )
        .order_by(col(ReportJob.id).desc())
    ).first()
    if running is not None and job_state(running) == "running":
        return running.id
    work = submitted_sessions(db, assignment)
    pool("reports").take(requester.id)
    try:
        job = ReportJob(
            assignment_id=assignment.id,
            requester_id=requester.id,
            language=language,
            total=len(work),
        )
        db.add(job)
        db.commit()  # the build's thread reads it, and the page after
        job_id = job.id
    except BaseException:
        pool("reports").give_back(requester.id)
        raise
    threading.Thread(
        target=_build, args=(job_id, work, language, requester.id), daemon=True
    ).start()
    return job_id


def _build(job_id: int, work: list[tuple[str, int, int]], language: str, requester_id: int):
    try:
        with tempfile.SpooledTemporaryFile(max_size=16 * 2**20) as spool:
            with zipfile.ZipFile(spool, "w", zipfile.ZIP_STORED) as archive:
                for done, (stem, session_id, number) in enumerate(work, start=1):
                    with read_session() as db:  # PDFs are compressed already
                        report = build_report(db, db.get(LabSession, session_id), number)
                    pdf = cached_pdf(report, language, None)
                    archive.writestr(f"{stem}_attempt-{number}.pdf", pdf)
                    _progress(job_id, done=done)
            spool.seek(0)
            _progress(job_id, status="done", content=spool.read())
        _delete_older(job_id)
    except Exception:  # noqa: BLE001 -- the page says it failed; the log says why
        log.exception("the class's reports zip %s failed", job_id)
        try:
            _progress(job_id, status="failed")
        except Exception:  # noqa: BLE001 -- the database itself is failing
            log.exception("could not mark the reports zip %s as failed", job_id)
    finally:
        pool("reports").give_back(requester_id)


def _progress(job_id: int, **fields) -> None:
    with write_session() as db:
        job = db.get(ReportJob, job_id)
        for name, value in fields.items():
            setattr(job, name, value)
        job.updated_at = utcnow()
        db.add(job)


def _delete_older(job_id: int) -> None:
    with write_session() as db:
        job = db.get(ReportJob, job_id)
        db.exec(
            delete(ReportJob).where(
                ReportJob.assignment_id == job.assignment_id,
                col(ReportJob.id) < job_id,
                ReportJob.status != "running",
            )
        )


def find_job(db: Session, assignment: Assignment, job_id: int) -> ReportJob | None:
    """Build ``job_id`` if it is one of ``assignment``'s (else None: a 404)."""
    job = db.get(ReportJob, job_id)
    return job if job is not None and job.assignment_id == assignment.id else None
