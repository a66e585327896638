"""The review's objects as dependencies: a teacher reaches only their own courses'
assignments and the sessions of students in them (anything else answers 404)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated

from fastapi import Depends, Request
from sqlmodel import Session

from app.accounts.deps import required_login
from app.core.exceptions import UserError
from app.models import Assignment, Course, LabSession, Role, User
from app.web.deps import ObjectId, SessionDep, SettingsDep


def teachers_assignment(db: Session, teacher: User, assignment_id: int) -> Assignment:
    """An assignment of one of the teacher's courses, else 404."""
    assignment = db.get(Assignment, assignment_id)
    course = db.get(Course, assignment.course_id) if assignment else None
    if course is None or course.teacher_id != teacher.id:
        raise UserError("review.no_such_assignment", status=404)
    return assignment


@dataclass
class CourseAssignment:
    course: Course
    assignment: Assignment


def course_assignment(
    request: Request,
    course_id: ObjectId,
    assignment_id: ObjectId,
    db: SessionDep,
    settings: SettingsDep,
) -> CourseAssignment:
    """``/courses/{course_id}/assignments/{assignment_id}`` of the logged-in teacher
    (found in the same trip to the thread pool)."""
    teacher = required_login(request, db, settings, Role.teacher)
    assignment = teachers_assignment(db, teacher, assignment_id)
    if assignment.course_id != course_id:
        raise UserError("review.no_such_assignment", status=404)
    return CourseAssignment(db.get(Course, course_id), assignment)


TeacherAssignment = Annotated[CourseAssignment, Depends(course_assignment)]


@dataclass
class Reviewable:
    session: LabSession
    assignment: Assignment
    course: Course


def reviewable_session(
    request: Request, session_id: ObjectId, db: SessionDep, settings: SettingsDep
) -> Reviewable:
    """A session of an assignment in one of the teacher's courses, else 404 (the teacher
    found in the same trip to the thread pool)."""
    teacher = required_login(request, db, settings, Role.teacher)
    session = db.get(LabSession, session_id)
    if session is None or session.assignment_id is None:
        raise UserError("review.no_such_session", status=404)
    assignment = teachers_assignment(db, teacher, session.assignment_id)
    return Reviewable(session, assignment, db.get(Course, assignment.course_id))


ReviewableSession = Annotated[Reviewable, Depends(reviewable_session)]
