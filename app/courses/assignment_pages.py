"""Teacher: create an assignment in a course (the review side comes with grading)."""

from __future__ import annotations

import math
from datetime import UTC, datetime

from fastapi import APIRouter, Request

from app.core.simulate import PRESETS
from app.courses.pages import course_context, own_course
from app.models import Assignment
from app.web.deps import CsrfProtected, FormDep, ObjectId, SessionDep, TeacherUser
from app.web.render import flash, redirect, render

router = APIRouter(prefix="/courses", tags=["pages: assignments"], include_in_schema=False)
METHODS = ("manual", "csv", "simulator")


class FormProblem(ValueError):
    def __init__(self, key: str, **params: object) -> None:
        super().__init__(key)
        self.key, self.params = key, params


OPTIONAL_NUMBERS = {  # name: (low, high) for fields that may be left empty
    "turn_on_bias_max_deg_h": (0, 10_000),
    "indexing_sigma_arcsec": (0, 36_000),
    "table_tilt_max_deg": (0, 30),
    "misalignment_max_deg": (0, 10),
    "true_heading_deg": (0, 360),
}
DEFAULTS = {
    "azimuth_min_deg": "0",
    "azimuth_max_deg": "360",
    "tolerance_heading_deg": "2",
    "tolerance_latitude_pct": "5",
    "tolerance_earth_rate_pct": "5",
    "max_attempts": "3",
    "late_policy": "accept",
    "reveal_truth": "after_grading",
    "turn_on_bias_max_deg_h": "",
    "indexing_sigma_arcsec": "",
    "table_tilt_max_deg": "",
    "misalignment_max_deg": "",
    "true_heading_deg": "",
    "instructions": "",
    "earth_rate_deg_h": "15.041",
    "min_readings": "10",
    "simulator_preset": "teaching-fog",
    "due_at": "",
}


def parse_assignment_form(form: dict) -> Assignment:
    """Validate the form; raises FormProblem naming the first wrong field."""
    form = {**DEFAULTS, **{k: v for k, v in form.items() if v is not None}}

    def number(name: str, low: float, high: float) -> float:
        try:
            value = float(str(form[name]).strip())
        except ValueError:
            raise FormProblem("assignment.not_a_number", field=name) from None
        if not (math.isfinite(value) and low <= value <= high):
            raise FormProblem("assignment.out_of_range", field=name, low=low, high=high)
        return value

    def optional(name: str) -> float | None:
        return None if not str(form[name]).strip() else number(name, *OPTIONAL_NUMBERS[name])

    title = str(form.get("title", "")).strip()
    if not title:
        raise FormProblem("assignment.title_required")
    methods = [m for m in form.get("methods", []) if m in METHODS]
    if not methods:
        raise FormProblem("assignment.methods_required")
    if form["simulator_preset"] not in PRESETS:
        raise FormProblem("assignment.bad_preset")
    if form["late_policy"] not in ("accept", "refuse"):
        raise FormProblem("assignment.bad_choice", field="late_policy")
    if form["reveal_truth"] not in ("never", "after_submission", "after_grading"):
        raise FormProblem("assignment.bad_choice", field="reveal_truth")
    due = None
    if str(form["due_at"]).strip():
        try:
            due = datetime.fromisoformat(str(form["due_at"]).strip())
        except ValueError:
            raise FormProblem("assignment.bad_due") from None
        if due.tzinfo is None:
            due = due.replace(tzinfo=UTC)
    return Assignment(
        course_id=0,
        title=title[:200],
        instructions=str(form["instructions"]).strip(),
        latitude_deg=number("latitude_deg", -90, 90),
        earth_rate_deg_h=number("earth_rate_deg_h", 1, 100),
        allowed_methods=",".join(methods),
        simulator_preset=form["simulator_preset"],
        min_readings=int(number("min_readings", 2, 100_000)),
        due_at=due,
        azimuth_min_deg=number("azimuth_min_deg", 0, 360),
        azimuth_max_deg=number("azimuth_max_deg", 0, 360),
        turn_on_bias_max_deg_h=optional("turn_on_bias_max_deg_h"),
        indexing_sigma_arcsec=optional("indexing_sigma_arcsec"),
        table_tilt_max_deg=optional("table_tilt_max_deg"),
        misalignment_max_deg=optional("misalignment_max_deg"),
        true_heading_deg=optional("true_heading_deg"),
        tolerance_heading_deg=number("tolerance_heading_deg", 0, 180),
        tolerance_latitude_pct=number("tolerance_latitude_pct", 0, 1000),
        tolerance_earth_rate_pct=number("tolerance_earth_rate_pct", 0, 1000),
        max_attempts=int(number("max_attempts", 0, 100)),
        late_policy=form["late_policy"],
        reveal_truth=form["reveal_truth"],
    )


def assignment_form_values(assignment: Assignment) -> dict:
    """The form fields of an existing assignment (for the settings form)."""

    def text(value) -> str:
        return "" if value is None else f"{value:g}" if isinstance(value, float) else str(value)

    values = {
        name: text(getattr(assignment, name))
        for name in (
            "title",
            "instructions",
            "latitude_deg",
            "earth_rate_deg_h",
            "simulator_preset",
            "min_readings",
            "azimuth_min_deg",
            "azimuth_max_deg",
            "turn_on_bias_max_deg_h",
            "indexing_sigma_arcsec",
            "table_tilt_max_deg",
            "misalignment_max_deg",
            "true_heading_deg",
            "tolerance_heading_deg",
            "tolerance_latitude_pct",
            "tolerance_earth_rate_pct",
            "max_attempts",
            "late_policy",
            "reveal_truth",
        )
    }
    values["methods"] = assignment.methods
    values["due_at"] = assignment.due_at.strftime("%Y-%m-%dT%H:%M") if assignment.due_at else ""
    return values


@router.post("/{course_id}/assignments", dependencies=[CsrfProtected])
def create_assignment(
    request: Request, course_id: ObjectId, teacher: TeacherUser, db: SessionDep, raw: FormDep
):
    """A teacher sets a lab: station, recording methods, gyro, truth ranges, rules."""
    course = own_course(db, teacher, course_id)
    form = {key: str(raw.get(key, "")) for key in raw if key not in ("methods", "csrf_token")}
    form["methods"] = raw.getlist("methods")
    try:
        assignment = parse_assignment_form(form)
    except FormProblem as problem:
        context = course_context(
            db,
            course,
            assignment_form={**DEFAULTS, **form},
            assignment_error=problem.key,
            assignment_error_params=problem.params,
        )
        return render(request, "courses/detail.html", context, 400)
    assignment.course_id = course.id
    db.add(assignment)
    db.commit()
    response = redirect(f"/courses/{course.id}/assignments/{assignment.id}")
    flash(response, request, "assignment.created", "success", title=assignment.title)
    return response
