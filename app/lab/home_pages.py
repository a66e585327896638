"""The lab's home page: the student's sessions, their assignments, and the form that starts
a practice session (or the session of an assignment)."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Form, Request
from sqlmodel import Session, select

from app.accounts.deps import CsrfProtected, CurrentUser
from app.core.exceptions import FieldProblems, UserError
from app.core.presets import PRESETS
from app.core.typed_numbers import parse_typed_number
from app.core.units import EARTH_RATE_DEG_H
from app.lab import partners
from app.lab import sessions as labsessions
from app.models import Assignment, Course, Enrollment, Extension, LabSession, Role, User, utcnow
from app.web.deps import MAX_ID, RowWriteSession, SessionDep
from app.web.i18n import translator
from app.web.render import flash, redirect, render, request_language

router = APIRouter(prefix="/lab", tags=["pages: lab"], include_in_schema=False)

STATIONS = [  # practice presets: (key, latitude, Earth rate)
    ("handout", 39.93, 15.04),
    ("beijing", 39.99, EARTH_RATE_DEG_H),
    ("shanghai", 31.23, EARTH_RATE_DEG_H),
    ("xian", 34.26, EARTH_RATE_DEG_H),
    ("harbin", 45.75, EARTH_RATE_DEG_H),
    ("guangzhou", 23.13, EARTH_RATE_DEG_H),
]
STATION_VALUES = {key: (latitude, rate) for key, latitude, rate in STATIONS}

# The new practice session form: its fields as the page shows them at first, and the
# label of each (the problems' summary names the fields by them).
NEW_SESSION_DEFAULTS = {
    "title": "",
    "station": "handout",
    "latitude_deg": "",
    "earth_rate_deg_h": "15.041",
    "rotation": "ccw",
    "heading_start_deg": "0",
    "latitude_start_deg": "0",
    "latitude_step_deg": "90",
    "preset": "teaching-fog",
}
NEW_SESSION_LABELS = {
    "title": "lab.session_title",
    "station": "lab.station",
    "latitude_deg": "lab.latitude",
    "earth_rate_deg_h": "lab.earth_rate",
    "rotation": "lab.rotation",
    "heading_start_deg": "lab.heading_start",
    "latitude_start_deg": "lab.latitude_start",
    "latitude_step_deg": "lab.latitude_step",
    "preset": "lab.preset",
}
NUMBER_FIELDS = (
    "latitude_deg",
    "earth_rate_deg_h",
    "heading_start_deg",
    "latitude_start_deg",
    "latitude_step_deg",
)


def my_assignments(db: Session, user: User) -> list[tuple[Assignment, Course]]:
    if user.role == Role.teacher:
        query = select(Assignment, Course).join(Course).where(Course.teacher_id == user.id)
    else:
        query = (
            select(Assignment, Course)
            .join(Course)
            .join(Enrollment, Enrollment.course_id == Course.id)
            .where(Enrollment.student_id == user.id)
        )
    return list(
        db.exec(
            query.where(Course.archived == False).order_by(Assignment.created_at.desc())  # noqa: E712
        ).all()
    )


def home_context(db: Session, user: User) -> dict[str, Any]:
    sessions = db.exec(
        select(LabSession)
        .where(partners.in_sessions_of(user.id))
        .order_by(LabSession.updated_at.desc())
    ).all()
    mine = {s.assignment_id: s for s in sessions if s.assignment_id is not None}
    extensions = {
        row.assignment_id: row.due_at
        for row in db.exec(select(Extension).where(Extension.student_id == user.id))
    }
    assignments = [
        {
            "assignment": assignment,
            "course": course,
            "session": mine.get(assignment.id),
            "due": extensions.get(assignment.id, assignment.due_at),
        }
        for assignment, course in my_assignments(db, user)
    ]
    return {
        "sessions": sessions,
        "assignments": assignments,
        "stations": STATIONS,
        "presets": sorted(PRESETS),
        "now": utcnow(),
        "new_session": NEW_SESSION_DEFAULTS,
        "new_session_labels": NEW_SESSION_LABELS,
        "problems": {},
    }


@router.get("")
def lab_home(request: Request, user: CurrentUser, db: SessionDep):
    return render(request, "lab/home.html", home_context(db, user))


def typed_settings(typed: dict[str, str]) -> tuple[labsessions.SessionSettings, dict]:
    """The new session form's typed text as settings, and the fields that are not numbers
    (a station from the list fills in its latitude and Earth rate)."""
    problems: dict[str, UserError] = {}
    numbers: dict[str, float | None] = {}
    station = STATION_VALUES.get(typed["station"])
    for name in NUMBER_FIELDS:
        if station is not None and name in ("latitude_deg", "earth_rate_deg_h"):
            numbers[name] = station[0] if name == "latitude_deg" else station[1]
            continue
        text = typed[name].strip()
        if not text:
            numbers[name] = None
            continue
        try:
            numbers[name] = parse_typed_number(text)
        except ValueError:
            numbers[name] = None
            problems[name] = UserError("form.not_a_number")
    settings = labsessions.SessionSettings(
        title=typed["title"],
        latitude_deg=numbers["latitude_deg"],
        earth_rate_deg_h=numbers["earth_rate_deg_h"],
        rotation=typed["rotation"],
        heading_start_deg=_angle(numbers["heading_start_deg"], 0.0),
        latitude_start_deg=_angle(numbers["latitude_start_deg"], 0.0),
        latitude_step_deg=_angle(numbers["latitude_step_deg"], 90.0),
        preset=typed["preset"],
    )
    return settings, problems


def _angle(value: float | None, blank: float) -> float:
    return blank if value is None else value


@router.post("/sessions", dependencies=[CsrfProtected, RowWriteSession])
def create_session(
    request: Request,
    user: CurrentUser,
    db: SessionDep,
    title: Annotated[str, Form(max_length=200)] = "",
    assignment_id: Annotated[int | None, Form(ge=1, le=MAX_ID)] = None,
    station: Annotated[str, Form(max_length=32)] = "handout",
    latitude_deg: Annotated[str, Form(max_length=64)] = "",
    earth_rate_deg_h: Annotated[str, Form(max_length=64)] = "",
    rotation: Annotated[str, Form(max_length=8)] = "ccw",
    heading_start_deg: Annotated[str, Form(max_length=64)] = "0",
    latitude_start_deg: Annotated[str, Form(max_length=64)] = "0",
    latitude_step_deg: Annotated[str, Form(max_length=64)] = "90",
    preset: Annotated[str, Form(max_length=32)] = "teaching-fog",
):
    """Start a session: a practice one (from the form, which comes back with every wrong
    field marked and everything typed kept), or the one of an assignment."""
    _ = translator(request_language(request))
    typed = {
        "title": title,
        "station": station,
        "latitude_deg": latitude_deg,
        "earth_rate_deg_h": earth_rate_deg_h,
        "rotation": rotation,
        "heading_start_deg": heading_start_deg,
        "latitude_start_deg": latitude_start_deg,
        "latitude_step_deg": latitude_step_deg,
        "preset": preset,
    }
    assignment = (
        labsessions.visible_assignment(db, user, assignment_id)
        if assignment_id is not None
        else None
    )
    settings, problems = typed_settings(typed)
    try:
        if problems:
            others = labsessions.settings_problems(settings, practice=assignment is None)
            raise FieldProblems({**others, **problems})
        session, created = labsessions.start_session(
            db, user, settings, assignment, _("lab.practice_title")
        )
    except FieldProblems as refused:
        if assignment is not None:
            return _back_with_error(request, refused.key)
        ordered = {name: refused.problems[name] for name in typed if name in refused.problems}
        context = {**home_context(db, user), "new_session": typed, "problems": ordered}
        return render(request, "lab/home.html", context, 400)
    except UserError as error:
        return _back_with_error(request, error.key)
    if created:
        db.commit()
    return redirect(f"/lab/sessions/{session.id}")


def _back_with_error(request: Request, key: str):
    response = redirect("/lab")
    flash(response, request, key, "error")
    return response
