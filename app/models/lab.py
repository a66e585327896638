"""Lab sessions: their positions' readings (takes and sample chunks), partners and archives.
Every change here needs an Alembic migration (tests check it)."""

from __future__ import annotations

from datetime import datetime
from enum import StrEnum

from sqlalchemy import BigInteger, Integer, UniqueConstraint
from sqlmodel import Field, SQLModel

from app.models.clock import utcnow

# 62-bit simulator seeds: BIGINT on PostgreSQL; SQLite's INTEGER already holds 64 bits.
SEED_TYPE = BigInteger().with_variant(Integer(), "sqlite")


DISCUSSION_MAX = 20_000  # characters of a student's discussion in the lab report


class InputMethod(StrEnum):
    """How a position's readings were recorded (a take's source), and the ways an
    assignment may allow (``api``: uploads, allowed with manual or csv)."""

    manual = "manual"  # typed into the grid
    csv = "csv"  # a pasted or uploaded file
    simulator = "simulator"  # streamed from the simulated gyro
    api = "api"  # uploaded through the REST API (a script or the serial bridge)


class Part(StrEnum):
    heading = "heading"  # part A: four positions in the horizontal plane
    latitude = "latitude"  # part B: four positions in the vertical north-south plane


class SessionStatus(StrEnum):
    """A lab session's state; a class row without a session is ``not_started``."""

    not_started = "not_started"
    in_progress = "in_progress"
    submitted = "submitted"
    returned = "returned"  # for revision, with the teacher's feedback
    graded = "graded"  # the grade released


class LabSession(SQLModel, table=True):
    """One student's run of the experiment (practice, or for an assignment).

    ``sim_*`` columns are the simulator's secret truth for this session: never sent to the
    student's browser.
    """

    __tablename__ = "lab_session"
    id: int | None = Field(default=None, primary_key=True)
    owner_id: int = Field(foreign_key="user.id", index=True)
    assignment_id: int | None = Field(default=None, foreign_key="assignment.id", index=True)
    title: str = Field(max_length=200)
    latitude_deg: float
    earth_rate_deg_h: float = 15.041
    heading_rotation: str = Field(default="ccw", max_length=3)
    heading_start_deg: float = 0.0
    latitude_start_deg: float = 0.0
    latitude_step_deg: float = 90.0
    min_readings: int = 10
    simulator_preset: str = Field(default="teaching-fog", max_length=32)
    sim_seed: int = Field(default=0, sa_type=SEED_TYPE)
    sim_azimuth_deg: float = 0.0
    sim_turns: int = 0
    sim_table_heading: int = 1  # position the virtual table is at, per part
    sim_table_latitude: int = 1
    stream_part: str | None = Field(default=None, max_length=8)  # a live recording under way
    stream_position: int | None = None
    sim_turn_on_bias_deg_h: float | None = None  # drawn per student by an assignment
    sim_indexing_sigma_arcsec: float | None = None
    # the virtual turntable, drawn by an assignment (None: from the seed and the preset)
    sim_pitch_deg: float | None = None
    sim_roll_deg: float | None = None
    sim_misalign_h_deg: float | None = None
    sim_misalign_v_deg: float | None = None
    # lab partners join with this code (assignments that allow groups); None: no partners
    partner_code: str | None = Field(default=None, max_length=16, unique=True)
    # 1-2-3-4-4-3-2-1: positions 5–8 revisit 4–1 (a linear drift cancels, and is fitted)
    symmetric_order: bool = False
    # part B's vertical plane: the horizontal dial (° clockwise from heading position 1)
    sim_plane_dial_deg: float | None = None
    # one gyro timeline per session: its clock (s since switch-on) at wall time sim_clock_at
    sim_clock_s: float = 0.0
    sim_clock_at: datetime | None = None
    status: str = Field(default=SessionStatus.in_progress, max_length=16)
    discussion: str = Field(default="", max_length=DISCUSSION_MAX)  # the lab report's draft
    created_at: datetime = Field(default_factory=utcnow)
    updated_at: datetime = Field(default_factory=utcnow)


class Take(SQLModel, table=True):
    """One recording of one position.  Re-recording supersedes, never deletes."""

    id: int | None = Field(default=None, primary_key=True)
    session_id: int = Field(foreign_key="lab_session.id", index=True, ondelete="CASCADE")
    part: str = Field(max_length=8)  # Part
    position: int
    angle_deg: float
    source: str = Field(max_length=16)  # InputMethod
    unit: str = Field(default="deg/h", max_length=8)
    n_samples: int
    created_at: datetime = Field(default_factory=utcnow)
    superseded_at: datetime | None = None
    # samples before this index are the transient after turning the table: kept, not used
    trim_start: int = 0
    frozen: bool = False  # an attempt refers to it: its samples never change again


class SampleChunk(SQLModel, table=True):
    """A block of a take's samples: little-endian float64 °/h (and optional seconds, and
    the gyro's optional case temperature in °C)."""

    __tablename__ = "sample_chunk"
    __table_args__ = (UniqueConstraint("take_id", "seq"),)
    id: int | None = Field(default=None, primary_key=True)
    take_id: int = Field(foreign_key="take.id", index=True, ondelete="CASCADE")
    seq: int
    values: bytes
    times: bytes | None = None
    temperatures: bytes | None = None


class SessionMember(SQLModel, table=True):
    """A lab partner: a student who shares another student's session for an assignment
    (sees it, records and submits in it, gets its grade)."""

    __tablename__ = "session_member"
    __table_args__ = (UniqueConstraint("session_id", "user_id"),)
    id: int | None = Field(default=None, primary_key=True)
    session_id: int = Field(foreign_key="lab_session.id", index=True, ondelete="CASCADE")
    user_id: int = Field(foreign_key="user.id", index=True, ondelete="CASCADE")
    joined_at: datetime = Field(default_factory=utcnow)


class ReadingArchive(SQLModel, table=True):
    """Readings of an earlier year a teacher uploaded (a class zip or readings CSV this or
    another GyroLab exported): only their copy keys are kept, to find copies of them."""

    __tablename__ = "reading_archive"
    id: int | None = Field(default=None, primary_key=True)
    teacher_id: int = Field(foreign_key="user.id", index=True, ondelete="CASCADE")
    name: str = Field(max_length=200)  # the file's name, as uploaded
    groups: int = 0  # the attempts (or files) whose readings gave keys
    uploaded_at: datetime = Field(default_factory=utcnow)
