"""Teacher review: the class's rows (status, results, auto-checks against each student's
truth -- ``app.lab.truth``), data fingerprints and status counts."""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from datetime import datetime
from functools import lru_cache
from types import SimpleNamespace

from sqlmodel import Session, col, select

from app.lab.copy_index import keyable_takes
from app.lab.partners import group_names, member_map
from app.lab.result_cache import KEY_COLUMNS, SUMMARIES, current_take_rows, data_keys
from app.lab.result_flags import flags_of_checks
from app.lab.results import SessionData, iter_takes_data
from app.lab.store import PARTS
from app.lab.truth import AutoCheck, Truth, auto_check, session_truth
from app.models import (
    Assignment,
    Attempt,
    Enrollment,
    Extension,
    LabSession,
    SessionStatus,
    Take,
    User,
)
from app.review.earlier_copies import earlier_copies
from app.review.evidence import SessionEvidence, class_findings, seen_notes, session_evidence
from app.review.take_summaries import TakeSummary, known_summary, take_summary

STATUSES = tuple(SessionStatus)


def data_fingerprint(
    takes: list, summaries: dict[int, TakeSummary]
) -> tuple[str | None, str | None]:
    """(hash of the exact samples, hash of the position means to 0.001 °/h) of current data
    (``takes``: the current takes in part and position order; ``summaries``: by take id)."""
    if not takes:
        return None, None
    exact, rounded = hashlib.sha256(), hashlib.sha256()
    for take in takes:
        summary = summaries[take.id]
        exact.update(f"{take.part}{take.position}".encode() + summary.digest)
        rounded.update(f"{take.part}{take.position}:{summary.mean:.3f};".encode())
    return exact.hexdigest(), rounded.hexdigest()


def data_flags(session: LabSession, takes: list, summaries: dict[int, TakeSummary]) -> list[dict]:
    """The data-quality flags the student sees, for every part with a result to flag."""
    flags = []
    for part in PARTS:
        checks = {t.position: summaries[t.id].checks for t in takes if t.part == part}
        if len(checks) >= 3:
            flags.extend(flags_of_checks(session, checks))
    return flags


# flags of a part's result, not of one position's readings: the submitted attempt keeps
# them (the per-position flags come from the current readings, ``data_flags``)
PART_FLAG_KEYS = frozenset(
    {
        "flag.unit_slip",
        "flag.closure",
        "flag.warming_up",
        "flag.warming_up_waited",
        "flag.warming_up_model",
        "flag.warming_up_model_waited",
    }
)


def part_flags(results: dict) -> list[dict]:
    """The part-level flags of a submitted attempt's results (a wrong unit, a closure
    residual, a gyro still warming up), each once; none from attempts made before
    results kept their flags."""
    seen, flags = set(), []
    for part in PARTS:
        for flag in (results.get(part) or {}).get("flags", []):
            mark = (flag["key"], json.dumps(flag.get("params", {}), sort_keys=True))
            if flag["key"] in PART_FLAG_KEYS and mark not in seen:
                seen.add(mark)
                flags.append(flag)
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
    data_evidence: SessionEvidence | None = None  # its own readings' findings and copy keys
    evidence: list[dict] = field(default_factory=list)  # all findings (app/review/evidence.py)
    _errors: dict | None = field(default=None, repr=False, compare=False)  # check_error's

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
        if self._errors is None:
            self._errors = {c.name: c.error for c in reversed(self.check.checks)}
        return self._errors.get(name)


SAMPLES_PER_READ = 2_000_000  # readings read (and held) at once for the sessions redone


def data_summaries(
    db: Session, assignment: Assignment, by_id: dict[int, LabSession]
) -> dict[int, tuple[list[dict], tuple[str | None, str | None], list, SessionEvidence]]:
    """Each session's data flags, fingerprints, current takes and data evidence (its own
    readings' findings and copy keys): put together once per version of its data
    (``result_cache.data_keys``) from its takes' summaries (``take_summaries``), so that
    the dashboard reads the samples only of takes it has not seen, and of the parts whose
    readings the students recorded themselves in sessions that changed."""
    sessions = list(by_id.values())
    take_rows = current_take_rows(db, sessions, assignment)
    keys = data_keys(db, sessions, assignment, take_rows)
    summaries = {sid: SUMMARIES.get(key) for sid, key in keys.items()}
    changed = [sid for sid, summary in summaries.items() if summary is None]
    created = _creation_times(db, [row for sid in changed for row in take_rows[sid]])
    takes = {
        sid: [
            _take_snapshot(sid, row, created[row[0]]) for row in take_rows[sid] if row[0] in created
        ]  # (a take deleted since it was listed has nothing to read)
        for sid in changed
    }
    batch: dict[int, list] = {}
    size = 0
    for session_id, current in takes.items():  # sessions a batch at a time: memory bounded
        batch[session_id] = current
        size += sum(take.n_samples for take in current)
        if size >= SAMPLES_PER_READ:
            _summarise(db, assignment, by_id, batch, summaries, keys)
            batch, size = {}, 0
    if batch:
        _summarise(db, assignment, by_id, batch, summaries, keys)
    return summaries


_KEY_NAMES = tuple(column.key for column in KEY_COLUMNS)


def _creation_times(db: Session, take_rows: list[tuple]) -> dict[int, datetime]:
    """take id → creation time, of the takes of ``take_rows`` (read only for the sessions
    redone: a class's every take's time cost more to read than its key).  By id, so that
    a take superseded since it was listed is still found."""
    ids = [row[0] for row in take_rows]
    created: dict[int, datetime] = {}
    for start in range(0, len(ids), 1000):
        created.update(
            db.connection()
            .execute(
                select(Take.id, Take.created_at).where(col(Take.id).in_(ids[start : start + 1000]))
            )
            .all()
        )
    return created


def _take_snapshot(session_id: int, row: tuple, created_at: datetime) -> SimpleNamespace:
    """A take as :func:`current_take_rows` read it, with its creation time."""
    columns = dict(zip(_KEY_NAMES, row, strict=True))
    return SimpleNamespace(session_id=session_id, created_at=created_at, **columns)


def _summarise(db, assignment, by_id, takes, summaries, keys) -> None:
    """The summaries of sessions whose data changed (``takes``: their current takes by
    session id), into ``summaries`` and ``SUMMARIES``: the takes not summarised yet and
    the takes the data evidence reads are read, in one pass."""
    session_ids = list(takes)
    known: dict[int, TakeSummary] = {}
    keyable = {take.id for sid in session_ids for take in keyable_takes(takes[sid])}
    wanted = []
    for sid in session_ids:
        for take in takes[sid]:
            summary = known_summary(take)
            if summary is not None:
                known[take.id] = summary
            if summary is None or take.id in keyable:
                wanted.append(take)
    own: dict[int, SessionData] = {}
    for item in iter_takes_data(db, wanted):
        take = item.take
        if take.id not in known:
            known[take.id] = take_summary(item)
        if take.id in keyable:
            own.setdefault(take.session_id, {}).setdefault(take.part, {})[take.position] = item
    for sid in session_ids:
        session = by_id[sid]
        current = [take for take in takes[sid] if take.id in known]  # (each has a chunk)
        data = {part: dict(sorted(p.items())) for part, p in sorted(own.get(sid, {}).items())}
        summary = (
            data_flags(session, current, known),
            data_fingerprint(current, known),
            current,
            session_evidence(assignment, session, data) if current else SessionEvidence(),
        )
        SUMMARIES.put(keys[sid], summary)
        summaries[sid] = summary


def latest_results(attempts: list[Attempt]) -> dict:
    """The latest attempt's results (shared between requests: read, never change)."""
    return _parsed_results(attempts[-1].results_json) if attempts else {}


@lru_cache(maxsize=1024)
def _parsed_results(results_json: str) -> dict:
    """A submitted attempt's results never change, and the dashboard reads every one of
    its class's on each view (≈ 25 µs each to parse): parsed once, by their text (the
    last 1,024: a few classes' worth, ≈ 20 kB each with the text)."""
    return json.loads(results_json)


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
        flags, prints, takes, evidence = summaries.get(
            session.id, ([], (None, None), [], SessionEvidence())
        )
        results = latest_results(history)
        flags = [*flags, *part_flags(results)]
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
            data_evidence=evidence,
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
    sessions_seen = seen_notes(db, [row.session.id for row in rows if row.session])
    class_findings(rows, sessions_seen, earlier_copies(db, assignment, rows))
    return rows


def session_row(db: Session, assignment: Assignment, session: LabSession) -> StudentRow | None:
    """The class row of ``session`` (its data evidence needs the whole class: copies)."""
    return next(
        (row for row in class_rows(db, assignment) if row.session and row.session.id == session.id),
        None,
    )


def status_counts(rows: list[StudentRow]) -> dict[str, int]:
    counts = dict.fromkeys(STATUSES, 0)
    for row in rows:
        counts[row.status] = counts.get(row.status, 0) + 1
    return counts
