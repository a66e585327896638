"""Teacher: create an assignment in a course (the review side comes with grading)."""

from __future__ import annotations

import math
from datetime import UTC, datetime
from typing import Annotated

from fastapi import APIRouter, Form, Request

from app.core.simulate import PRESETS
from app.deps import CsrfProtected, SessionDep, TeacherUser
from app.models import Assignment
from app.routers.courses import course_context, own_course
from app.web import flash, redirect, render

router = APIRouter(prefix="/courses", tags=["pages: assignments"], include_in_schema=False)
METHODS = ("manual", "csv", "simulator")


class FormProblem(ValueError):
    def __init__(self, key: str, **params: object) -> None:
        super().__init__(key)
        self.key, self.params = key, params


def parse_assignment_form(form: dict) -> Assignment:
    """Validate the form; raises FormProblem naming the first wrong field."""

    def number(name: str, low: float, high: float) -> float:
        try:
            value = float(str(form[name]).strip())
        except ValueError:
            raise FormProblem("assignment.not_a_number", field=name) from None
        if not (math.isfinite(value) and low <= value <= high):
            raise FormProblem("assignment.out_of_range", field=name, low=low, high=high)
        return value

    title = form["title"].strip()
    if not title:
        raise FormProblem("assignment.title_required")
    latitude = number("latitude_deg", -90, 90)
    earth_rate = number("earth_rate_deg_h", 1, 100)
    readings = number("min_readings", 1, 100_000)
    methods = [m for m in form["methods"] if m in METHODS]
    if not methods:
        raise FormProblem("assignment.methods_required")
    if form["simulator_preset"] not in PRESETS:
        raise FormProblem("assignment.bad_preset")
    due = None
    if form["due_at"].strip():
        try:
            due = datetime.fromisoformat(form["due_at"].strip())
        except ValueError:
            raise FormProblem("assignment.bad_due") from None
        if due.tzinfo is None:
            due = due.replace(tzinfo=UTC)
    return Assignment(
        course_id=0,
        title=title[:200],
        instructions=form["instructions"].strip(),
        latitude_deg=latitude,
        earth_rate_deg_h=earth_rate,
        allowed_methods=",".join(methods),
        simulator_preset=form["simulator_preset"],
        min_readings=int(readings),
        due_at=due,
    )


@router.post("/{course_id}/assignments", dependencies=[CsrfProtected])
def create_assignment(
    request: Request,
    course_id: int,
    teacher: TeacherUser,
    db: SessionDep,
    title: Annotated[str, Form(max_length=200)] = "",
    instructions: Annotated[str, Form(max_length=20_000)] = "",
    latitude_deg: Annotated[str, Form(max_length=32)] = "",
    earth_rate_deg_h: Annotated[str, Form(max_length=32)] = "15.041",
    methods: Annotated[list[str] | None, Form()] = None,
    simulator_preset: Annotated[str, Form(max_length=32)] = "teaching-fog",
    min_readings: Annotated[str, Form(max_length=8)] = "10",
    due_at: Annotated[str, Form(max_length=32)] = "",
):
    course = own_course(db, teacher, course_id)
    form = {
        "title": title,
        "instructions": instructions,
        "latitude_deg": latitude_deg,
        "earth_rate_deg_h": earth_rate_deg_h,
        "methods": methods or [],
        "simulator_preset": simulator_preset,
        "min_readings": min_readings,
        "due_at": due_at,
    }
    try:
        assignment = parse_assignment_form(form)
    except FormProblem as problem:
        context = course_context(
            db,
            course,
            assignment_form=form,
            assignment_error=problem.key,
            assignment_error_params=problem.params,
        )
        return render(request, "courses/detail.html", context, 400)
    assignment.course_id = course.id
    db.add(assignment)
    db.commit()
    response = redirect(f"/courses/{course.id}#assignments")
    flash(response, request, "assignment.created", "success", title=assignment.title)
    return response
