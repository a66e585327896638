"""SQLModel tables.  Every change here needs an Alembic migration (tests check it)."""

from __future__ import annotations

import secrets
from datetime import UTC, datetime
from enum import StrEnum

from sqlalchemy import BigInteger, Integer, UniqueConstraint
from sqlmodel import Field, SQLModel

# 62-bit simulator seeds: BIGINT on PostgreSQL; SQLite's INTEGER already holds 64 bits.
SEED_TYPE = BigInteger().with_variant(Integer(), "sqlite")


def utcnow() -> datetime:
    return datetime.now(UTC)


DISCUSSION_MAX = 20_000  # characters of a student's discussion in the lab report


class Role(StrEnum):
    admin = "admin"
    teacher = "teacher"
    student = "student"


JOIN_CODE_ALPHABET = "ABCDEFGHJKLMNPQRSTUVWXYZ23456789"  # no 0/O/1/I confusion


def new_join_code() -> str:
    """A course's enrolment code: 8 characters, 40 bits, typed or sent as a join link."""
    return "".join(secrets.choice(JOIN_CODE_ALPHABET) for _ in range(8))


class User(SQLModel, table=True):
    id: int | None = Field(default=None, primary_key=True)
    username: str = Field(max_length=64, unique=True, index=True)
    display_name: str = Field(max_length=128)
    email: str | None = Field(default=None, max_length=254)
    role: str = Field(max_length=16)
    password_hash: str = Field(max_length=255)
    must_change_password: bool = False
    language: str | None = Field(default=None, max_length=8)
    created_at: datetime = Field(default_factory=utcnow)
    # the teacher whose roster created this account (may reset its password); None for
    # accounts made by the CLI or an administrator
    created_by_id: int | None = Field(default=None, foreign_key="user.id", ondelete="SET NULL")


class AuthSession(SQLModel, table=True):
    """A server-side login session; the browser holds only a random token."""

    __tablename__ = "auth_session"
    id: int | None = Field(default=None, primary_key=True)
    token_hash: str = Field(max_length=64, unique=True, index=True)
    user_id: int = Field(foreign_key="user.id", index=True, ondelete="CASCADE")
    csrf_token: str = Field(max_length=64)
    created_at: datetime = Field(default_factory=utcnow)
    last_seen_at: datetime = Field(default_factory=utcnow)
    expires_at: datetime
    revoked_at: datetime | None = None
    window_start: datetime | None = None  # API calls with this cookie: one-minute windows
    window_count: int = 0


class LoginFailure(SQLModel, table=True):
    """One failed login, keyed by account or client address, for throttling."""

    __tablename__ = "login_failure"
    id: int | None = Field(default=None, primary_key=True)
    scope: str = Field(max_length=16)  # "account" | "address"
    key: str = Field(max_length=128, index=True)
    at: datetime = Field(default_factory=utcnow, index=True)


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


class SessionMember(SQLModel, table=True):
    """A lab partner: a student who shares another student's session for an assignment
    (sees it, records and submits in it, gets its grade)."""

    __tablename__ = "session_member"
    __table_args__ = (UniqueConstraint("session_id", "user_id"),)
    id: int | None = Field(default=None, primary_key=True)
    session_id: int = Field(foreign_key="lab_session.id", index=True, ondelete="CASCADE")
    user_id: int = Field(foreign_key="user.id", index=True, ondelete="CASCADE")
    joined_at: datetime = Field(default_factory=utcnow)


class ExternalIdentity(SQLModel, table=True):
    """An account's identity at an outside identity provider (OpenID Connect single
    sign-on): the provider's issuer and its stable subject id.  Such accounts have no
    usable password; they log in through the provider."""

    __tablename__ = "external_identity"
    __table_args__ = (UniqueConstraint("issuer", "subject"),)
    id: int | None = Field(default=None, primary_key=True)
    user_id: int = Field(foreign_key="user.id", index=True, ondelete="CASCADE")
    issuer: str = Field(max_length=500)
    subject: str = Field(max_length=255)
    created_at: datetime = Field(default_factory=utcnow)
    last_login_at: datetime | None = None


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


class ReadingArchive(SQLModel, table=True):
    """Readings of an earlier year a teacher uploaded (a class zip or readings CSV this or
    another GyroLab exported): only their copy keys are kept, to find copies of them."""

    __tablename__ = "reading_archive"
    id: int | None = Field(default=None, primary_key=True)
    teacher_id: int = Field(foreign_key="user.id", index=True, ondelete="CASCADE")
    name: str = Field(max_length=200)  # the file's name, as uploaded
    groups: int = 0  # the attempts (or files) whose readings gave keys
    uploaded_at: datetime = Field(default_factory=utcnow)


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


class Extension(SQLModel, table=True):
    """A later due date for one student of one assignment."""

    __table_args__ = (UniqueConstraint("assignment_id", "student_id"),)
    id: int | None = Field(default=None, primary_key=True)
    assignment_id: int = Field(foreign_key="assignment.id", index=True, ondelete="CASCADE")
    student_id: int = Field(foreign_key="user.id", index=True, ondelete="CASCADE")
    due_at: datetime
    created_at: datetime = Field(default_factory=utcnow)


class ApiToken(SQLModel, table=True):
    """A bearer token: a personal access token (named, scoped, revocable) or a short-lived
    token from ``POST /api/v1/auth/token``.  Only its SHA-256 is stored."""

    __tablename__ = "api_token"
    id: int | None = Field(default=None, primary_key=True)
    user_id: int = Field(foreign_key="user.id", index=True, ondelete="CASCADE")
    kind: str = Field(max_length=8)  # personal | login
    name: str = Field(default="", max_length=100)
    token_hash: str = Field(max_length=64, unique=True, index=True)
    prefix: str = Field(max_length=12)  # the first characters, to recognise a token
    scopes: str = Field(max_length=32)  # "read" or "read,upload"
    created_at: datetime = Field(default_factory=utcnow)
    expires_at: datetime | None = None
    last_used_at: datetime | None = None
    revoked_at: datetime | None = None
    window_start: datetime | None = None  # per-token rate limit: fixed one-minute windows
    window_count: int = 0


# --- LTI 1.3: GyroLab as a tool inside a university's LMS (app/lti) ---------------------------


class LtiPlatform(SQLModel, table=True):
    """An LMS registered with GyroLab (by an administrator or by dynamic registration):
    its issuer, the client id it gave GyroLab, its endpoints and its deployments."""

    __tablename__ = "lti_platform"
    __table_args__ = (UniqueConstraint("issuer", "client_id"),)
    id: int | None = Field(default=None, primary_key=True)
    name: str = Field(max_length=200)
    issuer: str = Field(max_length=500, index=True)
    client_id: str = Field(max_length=255)
    auth_login_url: str = Field(max_length=1000)  # the platform's OIDC authorization endpoint
    auth_token_url: str = Field(max_length=1000)  # OAuth 2 token endpoint (services)
    auth_audience: str | None = Field(default=None, max_length=1000)
    key_set_url: str = Field(max_length=1000)  # the platform's JWKS
    deployment_ids: str = Field(default="", max_length=4000)  # one per line
    registered_by: str = Field(default="admin", max_length=16)  # admin | dynamic
    created_at: datetime = Field(default_factory=utcnow)


class LtiKey(SQLModel, table=True):
    """GyroLab's signing keys (RS256): the newest unretired one signs; retired ones stay in
    the JWKS for a while so messages signed just before a rotation still verify."""

    __tablename__ = "lti_key"
    id: int | None = Field(default=None, primary_key=True)
    kid: str = Field(max_length=64, unique=True)
    private_pem: str = Field(max_length=8000)
    public_jwk: str = Field(max_length=4000)
    created_at: datetime = Field(default_factory=utcnow)
    retired_at: datetime | None = None


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


class LtiLaunchValue(SQLModel, table=True):
    """Short-lived values of the LTI handshake: nonces (used once), state parameters, a
    deep-linking launch's claims while the teacher picks an assignment."""

    __tablename__ = "lti_launch_value"
    key: str = Field(primary_key=True, max_length=200)
    value: str = Field(max_length=200_000)
    expires_at: datetime = Field(index=True)


class LtiContext(SQLModel, table=True):
    """An LMS course (an LTI context) and the GyroLab course it is linked to."""

    __tablename__ = "lti_context"
    __table_args__ = (UniqueConstraint("platform_id", "context_id"),)
    id: int | None = Field(default=None, primary_key=True)
    platform_id: int = Field(foreign_key="lti_platform.id", index=True, ondelete="CASCADE")
    context_id: str = Field(max_length=255)
    course_id: int = Field(foreign_key="course.id", index=True, ondelete="CASCADE")
    title: str = Field(default="", max_length=255)
    memberships_url: str | None = Field(default=None, max_length=1000)  # NRPS
    lineitems_url: str | None = Field(default=None, max_length=1000)  # AGS
    ags_scopes: str = Field(default="", max_length=1000)  # the AGS scopes the LMS granted
    roster_synced_at: datetime | None = None
    roster_problem: str | None = Field(default=None, max_length=500)


class LtiResourceLink(SQLModel, table=True):
    """An activity placed in the LMS (a resource link) and the assignment it opens, with
    the AGS line item its grades go to."""

    __tablename__ = "lti_resource_link"
    __table_args__ = (UniqueConstraint("platform_id", "resource_link_id"),)
    id: int | None = Field(default=None, primary_key=True)
    platform_id: int = Field(foreign_key="lti_platform.id", index=True, ondelete="CASCADE")
    resource_link_id: str = Field(max_length=255)
    context_row_id: int = Field(foreign_key="lti_context.id", index=True, ondelete="CASCADE")
    assignment_id: int | None = Field(
        default=None, foreign_key="assignment.id", index=True, ondelete="CASCADE"
    )
    lineitem_url: str | None = Field(default=None, max_length=1000)
    created_at: datetime = Field(default_factory=utcnow)


class LtiGradePost(SQLModel, table=True):
    """A released grade on its way to the LMS (AGS score): kept until the platform
    acknowledges it, retried with growing pauses, every failure visible to the teacher."""

    __tablename__ = "lti_grade_post"
    id: int | None = Field(default=None, primary_key=True)
    attempt_id: int = Field(foreign_key="attempt.id", index=True, ondelete="CASCADE")
    student_id: int = Field(foreign_key="user.id", index=True, ondelete="CASCADE")
    link_id: int = Field(foreign_key="lti_resource_link.id", index=True, ondelete="CASCADE")
    score: float
    maximum: float
    comment: str = Field(default="", max_length=20_000)
    status: str = Field(default="pending", max_length=8)  # pending | sent
    tries: int = 0
    last_error: str | None = Field(default=None, max_length=500)
    next_try_at: datetime = Field(default_factory=utcnow, index=True)
    created_at: datetime = Field(default_factory=utcnow)
    sent_at: datetime | None = None
