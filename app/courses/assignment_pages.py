"""Teacher: create an assignment in a course (its settings are edited on its dashboard)."""

from __future__ import annotations

from fastapi import APIRouter, Request

from app.accounts.deps import CsrfProtected, TeacherUser
from app.core.exceptions import FieldProblems
from app.courses.assignment_form import form_context, form_values, parse_assignment_form
from app.courses.deps import TeacherCourse
from app.courses.pages import course_context
from app.web.deps import FormDep, SessionDep
from app.web.render import flash, redirect, render

router = APIRouter(prefix="/courses", tags=["pages: assignments"], include_in_schema=False)


@router.post("/{course_id}/assignments", dependencies=[CsrfProtected])
def create_assignment(
    request: Request, course: TeacherCourse, teacher: TeacherUser, db: SessionDep, raw: FormDep
):
    """A teacher sets a lab: station, recording methods, gyro, truth ranges, rules."""
    form = {key: str(raw.get(key, "")) for key in raw if key not in ("methods", "csrf_token")}
    form["methods"] = raw.getlist("methods")
    try:
        assignment = parse_assignment_form(form, course.timezone)
    except FieldProblems as refused:
        context = course_context(
            db,
            course,
            assignment_form={**form_values(), **form},
            **form_context(refused.problems),
        )
        return render(request, "courses/detail.html", context, 400)
    assignment.course_id = course.id
    db.add(assignment)
    db.commit()
    response = redirect(f"/courses/{course.id}/assignments/{assignment.id}")
    flash(response, request, "assignment.created", "success", title=assignment.title)
    return response
