"""The courses' objects as dependencies: a teacher reaches only their own courses (another
teacher's answers 404, never revealing that it exists)."""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends

from app.accounts.deps import TeacherUser
from app.core.exceptions import UserError
from app.models import Course
from app.web.deps import ObjectId, SessionDep


def teachers_course(course_id: ObjectId, teacher: TeacherUser, db: SessionDep) -> Course:
    """``/courses/{course_id}`` of the logged-in teacher."""
    course = db.get(Course, course_id)
    if course is None or course.teacher_id != teacher.id:
        raise UserError("course.no_such_course", status=404)
    return course


TeacherCourse = Annotated[Course, Depends(teachers_course)]
