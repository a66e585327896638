"""Submitted attempts and what the teacher's review adds: grades, evidence notes, copies, the
class board, report jobs.  Every change here needs an Alembic migration (tests check it)."""

from __future__ import annotations

from datetime import datetime

from sqlalchemy import UniqueConstraint
from sqlmodel import Field, SQLModel

from app.models.clock import utcnow
from app.models.lab import DISCUSSION_MAX


class Attempt(SQLModel, table=True):
    """A submission: the data and results frozen at the moment of submitting."""

    id: int | None = Field(default=None, primary_key=True)
    session_id: int = Field(foreign_key="lab_session.id", index=True, ondelete="CASCADE")
    number: int
    take_ids: str = Field(max_length=2000)  # comma-separated current takes
    results_json: str
    submitted_at: datetime = Field(default_factory=utcnow)
    late: bool = False
    discussion: str = Field(default="", max_length=DISCUSSION_MAX)  # frozen with the attempt
    # its readings' copy keys are in ``copy_key`` (app/lab/copy_index.py)
    copy_indexed: bool = False
    # the teacher's review of this attempt: it stays with the attempt it was written on
    feedback: str = Field(default="", max_length=20_000)
    feedback_positions: str = Field(default="{}", max_length=20_000)  # JSON {"heading-1": "..."}
    points: float | None = None  # out of the assignment's max_points
    rubric_points: str = Field(default="{}", max_length=4000)  # JSON {"0": 35, "1": 20}
    letter: str | None = Field(default=None, max_length=32)  # optional letter grade
    returned_at: datetime | None = None  # returned for revision
    released_at: datetime | None = None  # graded and released
    seen_at: datetime | None = None  # the student opened the work after either


class GradeAmendment(SQLModel, table=True):
    """A released grade changed afterwards: what it was, who changed it, when and why (the
    student sees the change, the LMS gets the new score; the history is kept)."""

    __tablename__ = "grade_amendment"
    id: int | None = Field(default=None, primary_key=True)
    attempt_id: int = Field(foreign_key="attempt.id", index=True, ondelete="CASCADE")
    teacher_id: int | None = Field(default=None, foreign_key="user.id", ondelete="SET NULL")
    amended_at: datetime = Field(default_factory=utcnow)
    reason: str = Field(max_length=2000)
    points_before: float | None = None
    points_after: float | None = None
    letter_before: str | None = Field(default=None, max_length=32)
    letter_after: str | None = Field(default=None, max_length=32)
    feedback_before: str = Field(default="", max_length=20_000)


class EvidenceNote(SQLModel, table=True):
    """A teacher has looked at one data-evidence finding of a session (its check and part),
    with an optional note; the finding stays, marked as seen."""

    __tablename__ = "evidence_note"
    __table_args__ = (UniqueConstraint("session_id", "check", "part"),)
    id: int | None = Field(default=None, primary_key=True)
    session_id: int = Field(foreign_key="lab_session.id", index=True, ondelete="CASCADE")
    check: str = Field(max_length=16)
    part: str = Field(max_length=16)
    note: str = Field(default="", max_length=2000)
    teacher_id: int | None = Field(default=None, foreign_key="user.id", ondelete="SET NULL")
    seen_at: datetime = Field(default_factory=utcnow)


class CopyKey(SQLModel, table=True):
    """One offset-free pattern of a part's readings (``app.core.data_copies.copy_keys``):
    of a submitted attempt, or of an uploaded archive's group (``label``, ``attempt``)."""

    __tablename__ = "copy_key"
    id: int | None = Field(default=None, primary_key=True)
    key: str = Field(max_length=72, index=True)
    part: str = Field(max_length=8)
    attempt_id: int | None = Field(
        default=None, foreign_key="attempt.id", index=True, ondelete="CASCADE"
    )
    archive_id: int | None = Field(
        default=None, foreign_key="reading_archive.id", index=True, ondelete="CASCADE"
    )
    label: str = Field(default="", max_length=200)  # an archive's group
    attempt: int | None = None  # an archive's attempt number


class BoardSnapshot(SQLModel, table=True):
    """The class board as it stood at one moment, kept with the assignment (JSON of
    app/review/board.py's data)."""

    __tablename__ = "board_snapshot"
    id: int | None = Field(default=None, primary_key=True)
    assignment_id: int = Field(foreign_key="assignment.id", index=True, ondelete="CASCADE")
    teacher_id: int | None = Field(default=None, foreign_key="user.id", ondelete="SET NULL")
    created_at: datetime = Field(default_factory=utcnow)
    data: str = Field(max_length=2_000_000)


class ReportJob(SQLModel, table=True):
    """A class's reports zip built in the background (``reports/class_zip.py``): its
    progress, then the zip itself, kept until a newer one of the same assignment."""

    __tablename__ = "report_job"
    id: int | None = Field(default=None, primary_key=True)
    assignment_id: int = Field(foreign_key="assignment.id", index=True, ondelete="CASCADE")
    requester_id: int = Field(foreign_key="user.id", ondelete="CASCADE")
    language: str = Field(max_length=16)
    status: str = Field(default="running", max_length=16)  # running | done | failed
    done: int = 0
    total: int = 0
    content: bytes | None = None
    created_at: datetime = Field(default_factory=utcnow)
    updated_at: datetime = Field(default_factory=utcnow)
