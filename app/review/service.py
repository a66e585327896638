"""Teacher review: each student's truth, auto-checks, statuses, class rows and exports.

Heading truth: the session's secret simulator azimuth when every heading position came
from the simulated gyro; otherwise the assignment's known bench azimuth, if the teacher
gave one.  Latitude and Earth-rate truth: the assignment's station values.
"""

from __future__ import annotations

import hashlib
import json
import math
import random
from dataclasses import dataclass, field
from datetime import datetime

from sqlmodel import Session, select

from app.core.sinusoid import wrap180
from app.core.solve import percent_error
from app.lab.partners import group_names, member_map
from app.lab.result_cache import SUMMARIES, data_keys
from app.lab.results import SessionData, iter_current_data, quality_flags
from app.lab.store import PARTS, current_takes
from app.models import (
    Assignment,
    Attempt,
    Enrollment,
    Extension,
    InputMethod,
    LabSession,
    RevealTruth,
    SessionStatus,
    Take,
    User,
)

STATUSES = tuple(SessionStatus)


def draw_truth(assignment: Assignment, session: LabSession, rng: random.Random) -> None:
    """Give a new assignment session its secret truth from the teacher's ranges."""
    low, high = assignment.azimuth_min_deg, assignment.azimuth_max_deg
    span = (high - low) % 360.0 or (360.0 if high != low else 0.0)
    session.sim_azimuth_deg = (low + rng.random() * span) % 360.0
    if assignment.turn_on_bias_max_deg_h is not None:
        limit = abs(assignment.turn_on_bias_max_deg_h)
        session.sim_turn_on_bias_deg_h = rng.uniform(-limit, limit)
    session.sim_indexing_sigma_arcsec = assignment.indexing_sigma_arcsec
    if assignment.table_tilt_max_deg is not None:
        limit = abs(assignment.table_tilt_max_deg)
        session.sim_pitch_deg = rng.uniform(-limit, limit)
        session.sim_roll_deg = rng.uniform(-limit, limit)
    if assignment.misalignment_max_deg is not None:
        limit = abs(assignment.misalignment_max_deg)
        session.sim_misalign_h_deg = rng.uniform(-limit, limit)
        session.sim_misalign_v_deg = rng.uniform(-limit, limit)


@dataclass
class Truth:
    azimuth_deg: float | None
    latitude_deg: float
    earth_rate_deg_h: float
    turn_on_bias_deg_h: float | None
    azimuth_source: str | None  # "simulator" | "bench" | None


def session_truth(
    db: Session,
    session: LabSession,
    assignment: Assignment | None,
    takes: list[Take] | None = None,
) -> Truth:
    """The session's truth; ``takes`` (its current takes) saves a query when known."""
    from app.lab.sim import turn_on_bias

    if takes is None:
        takes = current_takes(db, session.id)
    heading_sources = {t.source for t in takes if t.part == "heading"}
    azimuth, source = None, None
    if heading_sources == {InputMethod.simulator}:
        azimuth, source = session.sim_azimuth_deg, "simulator"
    elif assignment is not None and assignment.true_heading_deg is not None:
        azimuth, source = assignment.true_heading_deg, "bench"
    uses_simulator = any(t.source == InputMethod.simulator for t in takes)
    return Truth(
        azimuth,
        session.latitude_deg,
        session.earth_rate_deg_h,
        turn_on_bias(session) if uses_simulator else None,
        source,
    )


@dataclass
class Check:
    name: str  # heading | latitude | earth_rate
    error: float | None  # degrees for heading, percent otherwise
    tolerance: float
    passed: bool | None  # None: cannot be checked


@dataclass
class AutoCheck:
    checks: list[Check] = field(default_factory=list)

    @property
    def passed(self) -> bool | None:
        decided = [c.passed for c in self.checks if c.passed is not None]
        if not decided:
            return None
        return all(decided)


def heading_error(azimuth_deg: float | None, truth_deg: float | None) -> float | None:
    """Estimate − truth wrapped to (−180°, 180°]: 359.5° against 0.5° is −1°, not 359°."""
    if azimuth_deg is None or truth_deg is None:
        return None
    return wrap180(azimuth_deg - truth_deg)


def auto_check(results: dict, truth: Truth, assignment: Assignment) -> AutoCheck:
    """Compare a results dict (the solve JSON of each part) with the truth."""
    heading = results.get("heading") or {}
    latitude = results.get("latitude") or {}
    checks = []
    error = heading_error(heading.get("azimuth_deg"), truth.azimuth_deg)
    checks.append(
        Check(
            "heading",
            error,
            assignment.tolerance_heading_deg,
            None if error is None else abs(error) <= assignment.tolerance_heading_deg,
        )
    )
    lat_error = (
        percent_error(latitude["latitude_deg"], truth.latitude_deg)
        if latitude.get("latitude_deg") is not None
        else None
    )
    checks.append(
        Check(
            "latitude",
            lat_error,
            assignment.tolerance_latitude_pct,
            None if lat_error is None else lat_error <= assignment.tolerance_latitude_pct,
        )
    )
    rate_error = (
        percent_error(latitude["earth_rate_deg_h"], truth.earth_rate_deg_h)
        if latitude.get("earth_rate_deg_h") is not None
        else None
    )
    checks.append(
        Check(
            "earth_rate",
            rate_error,
            assignment.tolerance_earth_rate_pct,
            None if rate_error is None else rate_error <= assignment.tolerance_earth_rate_pct,
        )
    )
    return AutoCheck(checks)


def truth_visible(session: LabSession, assignment: Assignment | None, attempts: int) -> bool:
    """May the student see their secret truth now?"""
    if assignment is None:
        return attempts > 0  # practice: after submitting
    if assignment.reveal_truth == RevealTruth.after_submission:
        return attempts > 0
    if assignment.reveal_truth == RevealTruth.after_grading:
        return session.status == SessionStatus.graded
    return False


def data_fingerprint(data: SessionData) -> tuple[str | None, str | None]:
    """(hash of the exact samples, hash of the position means to 0.001 °/h) of current data."""
    items = sorted(
        (item for positions in data.values() for item in positions.values()),
        key=lambda item: (item.take.part, item.take.position),
    )
    if not items:
        return None, None
    exact, rounded = hashlib.sha256(), hashlib.sha256()
    for item in items:
        take, values = item.take, item.values
        exact.update(f"{take.part}{take.position}".encode() + values.tobytes())
        mean = values.mean() if values.size else math.nan
        rounded.update(f"{take.part}{take.position}:{mean:.3f};".encode())
    return exact.hexdigest(), rounded.hexdigest()


def data_flags(session: LabSession, data: SessionData) -> list[dict]:
    """The data-quality flags the student sees, for every part with a result to flag."""
    flags = []
    for part in PARTS:
        positions = data.get(part, {})
        if len(positions) >= 3:
            flags.extend(quality_flags(session, positions))
    return flags


@dataclass
class StudentRow:
    student: User
    session: LabSession | None
    attempts: list[Attempt]
    status: str
    results: dict
    truth: Truth | None
    check: AutoCheck | None
    flags: list[dict]
    late: bool
    duplicate_of: list[str] = field(default_factory=list)
    prints: tuple[str | None, str | None] = (None, None)  # data_fingerprint of current data
    max_points: float = 100.0
    group: list[str] = field(default_factory=list)  # lab partners sharing the session
    due_at: datetime | None = None  # this student's due date (an extension, or the class's)
    extended: bool = False

    @property
    def submitted_at(self) -> datetime | None:
        return self.attempts[-1].submitted_at if self.attempts else None

    @property
    def latest(self) -> Attempt | None:
        return self.attempts[-1] if self.attempts else None

    @property
    def points(self) -> float | None:
        return self.latest.points if self.latest else None

    @property
    def letter(self) -> str:
        return (self.latest.letter or "") if self.latest else ""

    @property
    def released(self) -> bool:
        return self.status == SessionStatus.graded

    @property
    def releasable(self) -> bool:
        """Graded (points entered) but not yet released."""
        return self.points is not None and self.status in (
            SessionStatus.submitted,
            SessionStatus.returned,
        )

    def check_error(self, name: str) -> float | None:
        if self.check is None:
            return None
        return next((c.error for c in self.check.checks if c.name == name), None)


def data_summaries(
    db: Session, assignment: Assignment, by_id: dict[int, LabSession]
) -> dict[int, tuple[list[dict], tuple[str | None, str | None], list]]:
    """Each session's data flags, fingerprints and current takes: computed from the samples
    once per version of its data (``result_cache.data_keys``), so that the dashboard
    reads samples only of the sessions that changed since it was last drawn."""
    keys = data_keys(db, list(by_id.values()), assignment)
    summaries = {sid: SUMMARIES.get(key) for sid, key in keys.items()}
    changed = [sid for sid, summary in summaries.items() if summary is None]
    if changed:
        for session_id, data in iter_current_data(db, LabSession.id.in_(changed)):
            positions = [item for part in data.values() for item in part.values()]
            summary = (
                data_flags(by_id[session_id], data),
                data_fingerprint(data),
                [item.slim().take for item in positions],
            )
            SUMMARIES.put(keys[session_id], summary)
            summaries[session_id] = summary
        for session_id in changed:
            if summaries[session_id] is None:  # no recording yet
                summaries[session_id] = ([], (None, None), [])
                SUMMARIES.put(keys[session_id], summaries[session_id])
    return summaries


def latest_results(attempts: list[Attempt]) -> dict:
    return json.loads(attempts[-1].results_json) if attempts else {}


def class_rows(db: Session, assignment: Assignment) -> list[StudentRow]:
    """One row per enrolled student, with their submitted (latest attempt) results.

    A fixed number of queries whatever the class size: students, sessions, attempts, then
    every current position's samples streamed once (flags, fingerprints and truths are
    computed from them; nothing is re-solved -- results come from the attempts)."""
    students = db.exec(
        select(User)
        .join(Enrollment, Enrollment.student_id == User.id)
        .where(Enrollment.course_id == assignment.course_id)
        .order_by(User.username)
    ).all()
    in_assignment = LabSession.assignment_id == assignment.id
    sessions = {s.owner_id: s for s in db.exec(select(LabSession).where(in_assignment)).all()}
    for member_id, shared in member_map(db, assignment).items():
        sessions.setdefault(member_id, shared)  # a lab partner's row shows the group's session
    groups = group_names(db, [s.id for s in sessions.values()])
    attempts: dict[int, list[Attempt]] = {}
    for attempt in db.exec(
        select(Attempt)
        .join(LabSession, LabSession.id == Attempt.session_id)
        .where(in_assignment)
        .order_by(Attempt.session_id, Attempt.number)
    ).all():
        attempts.setdefault(attempt.session_id, []).append(attempt)
    summaries = data_summaries(db, assignment, {s.id: s for s in sessions.values()})

    rows = []
    fingerprints: dict[str, list[str]] = {}
    extensions = {
        row.student_id: row.due_at
        for row in db.exec(select(Extension).where(Extension.assignment_id == assignment.id))
    }
    for student in students:
        session = sessions.get(student.id)
        due = {
            "max_points": assignment.max_points,
            "due_at": extensions.get(student.id, assignment.due_at),
            "extended": student.id in extensions,
        }
        if session is None:
            rows.append(
                StudentRow(
                    student, None, [], SessionStatus.not_started, {}, None, None, [], False, **due
                )
            )
            continue
        history = attempts.get(session.id, [])
        flags, prints, takes = summaries.get(session.id, ([], (None, None), []))
        results = latest_results(history)
        truth = session_truth(db, session, assignment, takes)
        check = auto_check(results, truth, assignment) if history else None
        row = StudentRow(
            student,
            session,
            history,
            session.status,
            results,
            truth,
            check,
            list(flags),
            any(a.late for a in history),
            prints=prints,
            group=groups.get(session.id, []),
            **due,
        )
        rows.append(row)
        for print_ in prints:
            if print_:
                fingerprints.setdefault(print_, []).append(student.username)
    same_session = {row.student.username: row.session.id for row in rows if row.session is not None}
    for row in rows:
        for print_ in row.prints:
            others = [
                u
                for u in fingerprints.get(print_ or "", [])
                if u != row.student.username and same_session.get(u) != row.session.id
            ]
            row.duplicate_of.extend(u for u in others if u not in row.duplicate_of)
    return rows


def status_counts(rows: list[StudentRow]) -> dict[str, int]:
    counts = dict.fromkeys(STATUSES, 0)
    for row in rows:
        counts[row.status] = counts.get(row.status, 0) + 1
    return counts
