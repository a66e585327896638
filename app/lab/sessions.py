"""Creating lab sessions and finding the ones a user may use (shared by pages and the API)."""

from __future__ import annotations

import math
import random
from dataclasses import dataclass

from sqlalchemy import bindparam
from sqlmodel import Session, select

from app.core.exceptions import FieldProblems, UserError
from app.core.presets import PRESETS
from app.core.text_files import shown_name
from app.db import lock_rows
from app.lab.partners import ensure_partner_code, member_map
from app.lab.sim import new_truth
from app.lab.truth import draw_truth
from app.models import Assignment, Course, Enrollment, LabSession, Role, User, utcnow

# built once with bound parameters (each student's session start runs both)
ENROLMENT = select(Enrollment).where(
    Enrollment.course_id == bindparam("course_id"), Enrollment.student_id == bindparam("student_id")
)
OWN_SESSION_OF_ASSIGNMENT = select(LabSession).where(
    LabSession.assignment_id == bindparam("assignment_id"),
    LabSession.owner_id == bindparam("owner_id"),
)


def visible_assignment(db: Session, user: User, assignment_id: int) -> Assignment:
    """An assignment of a course the student is enrolled in (or the teacher owns)."""
    assignment = db.get(Assignment, assignment_id)
    course = db.get(Course, assignment.course_id) if assignment else None
    if assignment is None or course is None:
        raise UserError("lab.no_such_assignment", status=404)
    if user.role == Role.teacher:
        if course.teacher_id != user.id:
            raise UserError("lab.no_such_assignment", status=404)
        return assignment
    enrolled = db.exec(
        ENROLMENT, params={"course_id": assignment.course_id, "student_id": user.id}
    ).first()
    if enrolled is None or course.archived:
        raise UserError("lab.no_such_assignment", status=404)
    return assignment


@dataclass
class SessionSettings:
    title: str = ""
    latitude_deg: float | None = None
    earth_rate_deg_h: float | None = None
    rotation: str = "ccw"
    heading_start_deg: float = 0.0
    latitude_start_deg: float = 0.0
    latitude_step_deg: float = 90.0
    preset: str = "teaching-fog"
    symmetric_order: bool = False  # positions 5–8 revisit 4–1


def settings_problems(settings: SessionSettings, *, practice: bool) -> dict[str, UserError]:
    """Every impossible setting, by the form's field name (``practice``: a session of no
    assignment, whose station the student sets)."""
    problems: dict[str, UserError] = {}
    if practice:
        latitude, rate = settings.latitude_deg, settings.earth_rate_deg_h
        if latitude is None:
            problems["latitude_deg"] = UserError("lab.station_required")
        elif not (math.isfinite(latitude) and -90 <= latitude <= 90):
            problems["latitude_deg"] = UserError("lab.bad_latitude")
        if rate is None:
            problems["earth_rate_deg_h"] = UserError("lab.station_required")
        elif not (math.isfinite(rate) and 0 < rate < 1000):
            problems["earth_rate_deg_h"] = UserError("lab.bad_earth_rate")
    if settings.rotation not in ("ccw", "cw"):
        problems["rotation"] = UserError("rotation.unknown", rotation=str(settings.rotation)[:20])
    for name in ("heading_start_deg", "latitude_start_deg", "latitude_step_deg"):
        if not math.isfinite(getattr(settings, name)):
            problems[name] = UserError("lab.bad_angles")
    if "latitude_step_deg" not in problems and abs(settings.latitude_step_deg) < 1:
        problems["latitude_step_deg"] = UserError("lab.bad_angles")
    return problems


def start_session(
    db: Session,
    user: User,
    settings: SessionSettings,
    assignment: Assignment | None,
    default_title: str,
) -> tuple[LabSession, bool]:
    """A new session (added, not committed), or the existing one for this assignment.

    Returns (session, created).  Raises UserError for impossible settings.  In a row
    writer's transaction the student's row is locked first: "one session per student and
    assignment" is a read-check-write.
    """
    lock_rows(db, User, user.id)
    problems = settings_problems(settings, practice=assignment is None)
    if problems:
        raise FieldProblems(problems)
    if assignment is not None:
        existing = db.exec(
            OWN_SESSION_OF_ASSIGNMENT, params={"assignment_id": assignment.id, "owner_id": user.id}
        ).first()
        if existing is not None:  # one session per student and assignment
            return existing, False
        shared = member_map(db, assignment).get(user.id)
        if shared is not None:  # a lab partner's: the group's one session
            return shared, False
    seed, azimuth = new_truth()
    session = LabSession(
        owner_id=user.id,
        title=shown_name(settings.title)[:200],
        latitude_deg=0.0,
        heading_rotation=settings.rotation,
        heading_start_deg=settings.heading_start_deg,
        latitude_start_deg=settings.latitude_start_deg,
        latitude_step_deg=settings.latitude_step_deg,
        sim_seed=seed,
        sim_azimuth_deg=azimuth,
        sim_clock_at=utcnow(),  # the simulated gyro is switched on with the session
        symmetric_order=settings.symmetric_order,
    )
    if assignment is not None:
        draw_truth(assignment, session, random.SystemRandom())
        session.assignment_id = assignment.id
        session.latitude_deg = assignment.latitude_deg
        session.earth_rate_deg_h = assignment.earth_rate_deg_h
        session.simulator_preset = assignment.simulator_preset
        session.min_readings = assignment.min_readings
        session.title = session.title or assignment.title
        ensure_partner_code(db, session, assignment)
    else:
        session.latitude_deg = settings.latitude_deg
        session.earth_rate_deg_h = settings.earth_rate_deg_h
        session.simulator_preset = settings.preset if settings.preset in PRESETS else "teaching-fog"
        session.title = session.title or default_title
    db.add(session)
    return session, True
