"""REST API v1, teachers: their courses, an assignment's submissions, the class table."""

from __future__ import annotations

from fastapi import APIRouter
from fastapi.responses import Response
from sqlmodel import select

from app.accounts.api_auth import TeacherCaller
from app.core.jsonsafe import json_safe
from app.lab.attempts import grade_text
from app.models import Assignment, Course
from app.review.accuracy import class_accuracy
from app.review.board import board_data
from app.review.deps import teachers_assignment
from app.review.exports import class_table_response
from app.review.schemas import ClassAccuracyOut, CourseOut, SubmissionRow
from app.review.service import class_rows
from app.web.deps import ObjectId, SessionDep
from app.web.errors import API_ERRORS

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
