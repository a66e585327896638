"""A teacher's courses as the dashboard lists them (with each course's roster size)."""

from __future__ import annotations

from sqlalchemy import func
from sqlmodel import Session, select

from app.models import Course, Enrollment, User


def teacher_dashboard(db: Session, teacher: User) -> dict:
    """The teacher's dashboard: their courses (archived last, then by name) and the number
    of students enrolled in each."""
    courses = db.exec(
        select(Course).where(Course.teacher_id == teacher.id).order_by(Course.archived, Course.name)
    ).all()
    counts = dict(
        db.exec(
            select(Enrollment.course_id, func.count(Enrollment.id))
            .where(Enrollment.course_id.in_([course.id for course in courses]))
            .group_by(Enrollment.course_id)
        ).all()
    )
    return {
        "courses": courses,
        "counts": {course.id: counts.get(course.id, 0) for course in courses},
    }
