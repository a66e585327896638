"""The review API's response models: a teacher's courses and the class's submissions."""

from __future__ import annotations

from datetime import datetime

from pydantic import BaseModel


class CourseOut(BaseModel):
    id: int
    name: str
    archived: bool
    assignments: list[dict]


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
