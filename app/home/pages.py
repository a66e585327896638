"""The dashboard: what a teacher or a student sees after logging in."""

from __future__ import annotations

from fastapi import APIRouter, Request
from sqlmodel import select

from app.accounts.deps import CurrentUser
from app.courses.listing import teacher_dashboard
from app.lab.attempts import latest_attempt, notices, released_grade, shown_to_student
from app.lab.partners import in_sessions_of
from app.models import Assignment, Course, Enrollment, LabSession, Role, User
from app.web.deps import SessionDep
from app.web.render import redirect, render

router = APIRouter(tags=["pages: home"], include_in_schema=False)


@router.get("/")
def dashboard(request: Request, user: CurrentUser, db: SessionDep):
    if user.role == Role.admin:
        return redirect("/admin/accounts")
    if user.role == Role.teacher:
        return render(request, "dashboard/teacher.html", teacher_dashboard(db, user))
    rows = db.exec(
        select(Course, User)
        .join(Enrollment, Enrollment.course_id == Course.id)
        .join(User, User.id == Course.teacher_id)
        .where(Enrollment.student_id == user.id, Course.archived == False)  # noqa: E712
        .order_by(Course.name)
    ).all()
    work = []
    for session, assignment in db.exec(
        select(LabSession, Assignment)
        .join(Assignment, Assignment.id == LabSession.assignment_id)
        .where(in_sessions_of(user.id))
        .order_by(LabSession.updated_at.desc())
    ).all():
        latest = latest_attempt(db, session.id)
        given = latest is not None and shown_to_student(latest)
        work.append(
            {
                "session": session,
                "assignment": assignment,
                "grade": released_grade(session, [latest] if latest else [], assignment),
                "feedback": latest.feedback if given else "",
            }
        )
    return render(
        request,
        "dashboard/student.html",
        {"courses": rows, "work": work, "notices": notices(db, user)},
    )
