"""REST API v1, teachers: their courses, an assignment's submissions, the class table, the
readings of earlier years kept to find copies of them."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, File, UploadFile
from fastapi.responses import Response
from sqlmodel import select

from app.accounts.api_auth import TeacherCaller, TeacherUploadCaller
from app.core.jsonsafe import json_safe
from app.lab.attempts import grade_text
from app.models import Assignment, Course, ReadingArchive
from app.review import archives
from app.review.accuracy import class_accuracy
from app.review.board import board_data
from app.review.deps import teachers_assignment
from app.review.exports import class_table_response, class_table_xlsx_response
from app.review.schemas import ArchiveOut, ClassAccuracyOut, CourseOut, SubmissionRow
from app.review.service import class_rows
from app.web.deps import ObjectId, SessionDep
from app.web.errors import API_ERRORS
from app.web.workbooks import XLSX_MEDIA_TYPE

router = APIRouter(prefix="/api/v1", tags=["api: teachers"], responses=API_ERRORS)


@router.get("/courses", response_model=list[CourseOut])
def list_courses(caller: TeacherCaller, db: SessionDep):
    """Teachers: their courses with the assignments in each."""
    courses = db.exec(
        select(Course).where(Course.teacher_id == caller.user.id).order_by(Course.name)
    ).all()
    out = []
    for course in courses:
        assignments = db.exec(select(Assignment).where(Assignment.course_id == course.id)).all()
        out.append(
            CourseOut(
                id=course.id,
                name=course.name,
                archived=course.archived,
                assignments=[
                    {
                        "id": a.id,
                        "title": a.title,
                        "due_at": a.due_at.isoformat() if a.due_at else None,
                    }
                    for a in assignments
                ],
            )
        )
    return out


@router.get(
    "/assignments/{assignment_id}/submissions",
    response_model=list[SubmissionRow],
)
def list_submissions(assignment_id: ObjectId, caller: TeacherCaller, db: SessionDep):
    """Teachers: one row per enrolled student with their latest submitted results."""
    assignment = teachers_assignment(db, caller.user, assignment_id)
    rows = []
    for row in class_rows(db, assignment):
        rows.append(
            SubmissionRow(
                username=row.student.username,
                display_name=row.student.display_name,
                status=row.status,
                session_id=row.session.id if row.session else None,
                attempts=len(row.attempts),
                submitted_at=row.submitted_at,
                late=row.late,
                results=row.results,
                heading_error_deg=row.check_error("heading"),
                latitude_error_percent=row.check_error("latitude"),
                earth_rate_error_percent=row.check_error("earth_rate"),
                auto_check=None if row.check is None else row.check.passed,
                grade=grade_text(row.latest, assignment) or None,
                points=row.points,
                max_points=assignment.max_points,
                released=row.released,
                evidence=row.evidence,
            )
        )
    return rows


@router.get("/assignments/{assignment_id}/accuracy", response_model=ClassAccuracyOut)
def class_accuracy_api(assignment_id: ObjectId, caller: TeacherCaller, db: SessionDep):
    """Teachers: the class's errors against the accuracy planner's 1σ for each group's
    dwell and order -- whether the scatter agrees with the gyro's noise (χ², 95 %)."""
    assignment = teachers_assignment(db, caller.user, assignment_id)
    return class_accuracy(assignment, class_rows(db, assignment))


@router.get("/assignments/{assignment_id}/board", response_model=dict)
def class_board_api(
    assignment_id: ObjectId, caller: TeacherCaller, db: SessionDep, names: bool = False
):
    """Teachers: the class board -- each group's heading error, latitude and Earth rate with
    its 1σ (submitted attempt, else current data), the pooled latitude and Earth rate with
    their standard errors (inverse-variance weighted, Birge-widened), outliers beyond 3σ.
    Groups are numbered; ``names=true`` adds their usernames."""
    assignment = teachers_assignment(db, caller.user, assignment_id)
    return json_safe(board_data(db, assignment, class_rows(db, assignment), names))


@router.get(
    "/assignments/{assignment_id}/export.csv",
    response_class=Response,
    responses={200: {"content": {"text/csv": {}}, "description": "the class table"}},
)
def export_submissions(assignment_id: ObjectId, caller: TeacherCaller, db: SessionDep):
    """Teachers: the class table as CSV (UTF-8 with BOM)."""
    assignment = teachers_assignment(db, caller.user, assignment_id)
    return class_table_response(db, assignment)


@router.get(
    "/assignments/{assignment_id}/export.xlsx",
    response_class=Response,
    responses={200: {"content": {XLSX_MEDIA_TYPE: {}}, "description": "the class table"}},
)
def export_submissions_xlsx(assignment_id: ObjectId, caller: TeacherCaller, db: SessionDep):
    """Teachers: the class table as an Excel workbook (the CSV's columns; student numbers
    as text, results and points as numbers)."""
    assignment = teachers_assignment(db, caller.user, assignment_id)
    return class_table_xlsx_response(db, assignment)


def _archive_out(archive: ReadingArchive) -> ArchiveOut:
    return ArchiveOut(
        id=archive.id, name=archive.name, groups=archive.groups, uploaded_at=archive.uploaded_at
    )


@router.get("/archives", response_model=list[ArchiveOut])
def list_archives(caller: TeacherCaller, db: SessionDep):
    """Teachers: their uploads of earlier years' readings, newest first."""
    return [_archive_out(a) for a in archives.teacher_archives(db, caller.user.id)]


@router.post("/archives", response_model=ArchiveOut, status_code=201)
def upload_archive(
    caller: TeacherUploadCaller,
    db: SessionDep,
    readings: Annotated[UploadFile | None, File(description="a class zip or readings CSV")] = None,
):
    """Teachers (``upload`` scope): readings of an earlier year -- a class zip as GyroLab
    exports it (``<group>/attempt-<n>.csv``) or one readings CSV -- whose copy keys are kept
    so that copies of them in the teacher's courses are flagged (``copy_earlier``).  Only
    the keys and the groups' labels are stored, never the readings."""
    stored = archives.upload_archive(db, caller.user.id, readings)
    db.commit()
    return _archive_out(stored)


@router.delete("/archives/{archive_id}", status_code=204, response_class=Response)
def delete_archive(archive_id: ObjectId, caller: TeacherUploadCaller, db: SessionDep):
    """Teachers (``upload`` scope): forget an upload and its keys (another teacher's: 404)."""
    archives.delete_archive(db, caller.user.id, archive_id)
    db.commit()
    return Response(status_code=204)
