"""The review API's response models: a teacher's courses and the class's submissions."""

from __future__ import annotations

from datetime import datetime
from typing import Literal

from pydantic import BaseModel, Field


class CourseOut(BaseModel):
    id: int
    name: str
    archived: bool
    assignments: list[dict]


class ArchiveOut(BaseModel):
    """An upload of earlier years' readings: only its copy keys are kept."""

    id: int
    name: str = Field(description="the file's name, as uploaded")
    groups: int = Field(description="the attempts (or files) whose readings gave copy keys")
    uploaded_at: datetime


class SubmissionRow(BaseModel):
    username: str
    display_name: str
    status: str
    session_id: int | None
    attempts: int
    submitted_at: datetime | None
    late: bool
    results: dict
    heading_error_deg: float | None
    latitude_error_percent: float | None
    earth_rate_error_percent: float | None
    auto_check: bool | None
    grade: str | None  # "85 / 100 (B+)": the teacher's, released or not
    points: float | None
    max_points: float
    released: bool
    evidence: list[dict] = Field(
        default_factory=list,
        description="data evidence on the readings the group recorded itself: "
        "check (scatter_low, scatter_high, smooth, digits, off_grid, off_class_grid, copy, "
        "copy_earlier, handout, too_close, time_order, time_step), part, and the check's numbers "
        "(copy_earlier: sources, each a group with its attempts and its assignment and "
        "course, or the uploaded archive)",
    )


class AccuracyRow(BaseModel):
    groups: int = Field(description="submitted groups compared")
    ratio: float = Field(description="R = RMS of error/predicted σ over the groups")
    low: float = Field(description="R's 95 % range with only the gyro's noise: lower end")
    high: float
    verdict: Literal["agrees", "larger", "smaller", "too_few"]
    median_dwell_s: float
    predicted_sigma: float = Field(description="the plan's 1σ at the median dwell")
    measured_rms: float = Field(description="RMS of the groups' errors against their truth")


class ClassAccuracyOut(BaseModel):
    """Per quantity (heading °, latitude °, earth_rate °/h): the class against the plan."""

    heading: AccuracyRow | None = None
    latitude: AccuracyRow | None = None
    earth_rate: AccuracyRow | None = None
