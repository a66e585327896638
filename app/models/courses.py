"""Courses, their students, and the assignments set for them.  Every change here needs an
Alembic migration (tests check it)."""

from __future__ import annotations

import secrets
from datetime import datetime
from enum import StrEnum

from sqlalchemy import UniqueConstraint
from sqlmodel import Field, SQLModel

from app.models.clock import utcnow

JOIN_CODE_ALPHABET = "ABCDEFGHJKLMNPQRSTUVWXYZ23456789"  # no 0/O/1/I confusion


def new_join_code() -> str:
    """A course's enrolment code: 8 characters, 40 bits, typed or sent as a join link."""
    return "".join(secrets.choice(JOIN_CODE_ALPHABET) for _ in range(8))


class Course(SQLModel, table=True):
    id: int | None = Field(default=None, primary_key=True)
    name: str = Field(max_length=200)
    teacher_id: int = Field(foreign_key="user.id", index=True)
    archived: bool = False
    # students join with this code (or the join link): the student's consent to enrolment
    join_code: str = Field(default_factory=new_join_code, max_length=16, unique=True, index=True)
    # due dates are typed and shown in this IANA zone (None: the server's GYROLAB_TIMEZONE);
    # every datetime is stored in UTC
    timezone: str | None = Field(default=None, max_length=64)
    created_at: datetime = Field(default_factory=utcnow)


class Enrollment(SQLModel, table=True):
    __table_args__ = (UniqueConstraint("course_id", "student_id"),)
    id: int | None = Field(default=None, primary_key=True)
    course_id: int = Field(foreign_key="course.id", index=True, ondelete="CASCADE")
    student_id: int = Field(foreign_key="user.id", index=True)
    created_at: datetime = Field(default_factory=utcnow)


class LatePolicy(StrEnum):
    accept = "accept"  # and flag the attempt late
    refuse = "refuse"


class RevealTruth(StrEnum):
    """When students may see their secret truth."""

    never = "never"
    after_submission = "after_submission"
    after_grading = "after_grading"


class Assignment(SQLModel, table=True):
    """A lab a teacher sets for a course; station values are the truth for percent errors."""

    id: int | None = Field(default=None, primary_key=True)
    course_id: int = Field(foreign_key="course.id", index=True, ondelete="CASCADE")
    title: str = Field(max_length=200)
    instructions: str = Field(default="", max_length=20_000)
    latitude_deg: float
    earth_rate_deg_h: float = 15.041
    allowed_methods: str = Field(default="manual,csv,simulator", max_length=64)
    simulator_preset: str = Field(default="teaching-fog", max_length=32)
    min_readings: int = 10
    due_at: datetime | None = None
    created_at: datetime = Field(default_factory=utcnow)
    # secret truth drawn per student for simulator runs
    azimuth_min_deg: float = 0.0
    azimuth_max_deg: float = 360.0
    turn_on_bias_max_deg_h: float | None = None  # None: the preset's own turn-on bias
    indexing_sigma_arcsec: float | None = None  # None: the preset's own
    table_tilt_max_deg: float | None = None  # pitch and roll drawn in ±max; None: preset's σ
    misalignment_max_deg: float | None = None  # gyro axis vs dial zero, ±max; None: preset's σ
    true_heading_deg: float | None = None  # a real bench's known start azimuth, if any
    # a real gyro's Allan characterisation (JSON: fitted terms and rate), uploaded by the
    # teacher: readings typed, uploaded or sent by the bridge then get the "allan" σ
    gyro_characterisation: str | None = Field(default=None, max_length=4000)
    # auto-check tolerances
    tolerance_heading_deg: float = 2.0
    tolerance_latitude_pct: float = 5.0
    tolerance_earth_rate_pct: float = 5.0
    max_attempts: int = 3  # 0 = unlimited
    late_policy: str = Field(default=LatePolicy.accept, max_length=8)
    reveal_truth: str = Field(default=RevealTruth.after_grading, max_length=20)
    max_points: float = 100.0
    group_size: int = 1  # lab partners: up to this many students share one session (1–3)
    # optional rubric: JSON [{"name": "...", "points": 40}, ...] adding up to max_points
    rubric: str = Field(default="[]", max_length=20_000)

    @property
    def methods(self) -> list[str]:
        return [m for m in self.allowed_methods.split(",") if m]


class Extension(SQLModel, table=True):
    """A later due date for one student of one assignment."""

    __table_args__ = (UniqueConstraint("assignment_id", "student_id"),)
    id: int | None = Field(default=None, primary_key=True)
    assignment_id: int = Field(foreign_key="assignment.id", index=True, ondelete="CASCADE")
    student_id: int = Field(foreign_key="user.id", index=True, ondelete="CASCADE")
    due_at: datetime
    created_at: datetime = Field(default_factory=utcnow)
