"""The class's downloads for a teacher: the class table (CSV) and every submitted attempt
(zip).  One function each, shared by the dashboard and the REST API."""

from __future__ import annotations

from fastapi.responses import StreamingResponse
from sqlmodel import Session

from app.models import Assignment
from app.review.service import class_rows, export_rows
from app.web.exports import SubmittedWork, assignment_zip, csv_table


def class_table_response(db: Session, assignment: Assignment) -> StreamingResponse:
    """The class table as CSV (UTF-8 with BOM, cells safe to open in a spreadsheet)."""
    return StreamingResponse(
        csv_table(export_rows(class_rows(db, assignment))),
        media_type="text/csv; charset=utf-8",
        headers={"Content-Disposition": f'attachment; filename="assignment-{assignment.id}.csv"'},
    )


def class_zip_response(db: Session, assignment: Assignment) -> StreamingResponse:
    """The class table plus every submitted attempt's own data (CSV and JSON with its
    results): what the students submitted, never what they changed afterwards."""
    rows = class_rows(db, assignment)
    work = [
        SubmittedWork(row.student.username, row.session.id, list(row.attempts))
        for row in rows
        if row.session is not None and row.attempts
    ]
    return StreamingResponse(
        assignment_zip(export_rows(rows), work),
        media_type="application/zip",
        headers={"Content-Disposition": f'attachment; filename="assignment-{assignment.id}.zip"'},
    )
