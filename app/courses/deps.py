"""The courses' objects as dependencies: a teacher reaches only their own courses (another
teacher's answers 404, never revealing that it exists)."""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends, Request

from app.accounts.deps import required_login
from app.core.exceptions import UserError
from app.models import Course, Role
from app.web.deps import ObjectId, SessionDep, SettingsDep


def teachers_course(
    request: Request, course_id: ObjectId, db: SessionDep, settings: SettingsDep
) -> Course:
    """``/courses/{course_id}`` of the logged-in teacher (found in the same trip to the
    thread pool)."""
    teacher = required_login(request, db, settings, Role.teacher)
    course = db.get(Course, course_id)
    if course is None or course.teacher_id != teacher.id:
        raise UserError("course.no_such_course", status=404)
    return course


TeacherCourse = Annotated[Course, Depends(teachers_course)]
