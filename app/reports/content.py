"""What a lab report holds: one session's data and results -- its current draft, or one
submitted attempt exactly as it was submitted -- with the review the student was given.

The numbers are the ones the pages show: the same stored takes solved by the same
``solve_part`` (which also writes the worked steps and the data-quality flags).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from datetime import datetime

from sqlmodel import Session, select

from app.core.exceptions import UserError
from app.core.presets import PRESETS
from app.lab.attempts import comments_of, grade_text, shown_to_student
from app.lab.exports import Selection, solve_takes
from app.lab.partners import members_of
from app.lab.results import PartResult
from app.lab.store import is_editable
from app.lab.truth import AutoCheck, Truth, auto_check, session_truth, truth_visible
from app.models import Assignment, Attempt, Course, LabSession, User, utcnow

FULL_TABLE_LIMIT = 50  # readings per position printed in full; longer records are attached
# readings attached to the PDF as CSV at most (≈ 8 MB of CSV, 1.5 MB in the PDF, a second to
# write); a logger's million per position made a 29 MB PDF in 18 s, so beyond this the
# report says where every reading is (the session's CSV export) instead
ATTACH_LIMIT = 200_000


@dataclass
class Report:
    """Everything the report shows, gathered once (the renderer only lays it out)."""

    session: LabSession
    assignment: Assignment | None
    course: Course | None
    members: list[User]
    attempt: Attempt | None  # None: the session's current, unsubmitted data
    results: dict[str, PartResult]
    discussion: str
    generated_at: datetime
    sources: list[str] = field(default_factory=list)
    preset_name: str | None = None
    truth: Truth | None = None
    check: AutoCheck | None = None
    feedback: str = ""
    comments: dict[str, str] = field(default_factory=dict)
    grade: str = ""
    take_keys: tuple = ()  # (id, trim) of each take shown: what the PDF cache keys on

    @property
    def longest_record(self) -> int:
        sizes = [item.n for outcome in self.results.values() for item in outcome.positions.values()]
        return max(sizes, default=0)

    @property
    def readings_in_full(self) -> bool:
        """Short records are printed reading by reading; long ones are summarised and the
        samples attached to the PDF as CSV."""
        return self.longest_record <= FULL_TABLE_LIMIT

    @property
    def stored_readings(self) -> int:
        """Every reading of the takes shown, those trimmed off included (what the CSV holds)."""
        return sum(n_samples for _id, _trim, n_samples in self.take_keys)

    @property
    def readings_attached(self) -> bool:
        """Long records' readings go with the PDF as CSV, up to :data:`ATTACH_LIMIT`."""
        return not self.readings_in_full and self.stored_readings <= ATTACH_LIMIT

    @property
    def uncertainty_notes(self) -> list[tuple[list[str], str]]:
        """What each part's 1σ assumes, one note per model: (the parts it covers, the
        model), so two parts with the same model share one footnote."""
        notes: dict[str, list[str]] = {}
        for part, outcome in self.results.items():
            model = outcome.result.fit.uncertainty_model if outcome.result else None
            if model:
                notes.setdefault(model, []).append(part)
        return [(parts, model) for model, parts in notes.items()]

    def readings_rows(self, part: str) -> list[list[float | None]]:
        """Row i: the i-th used reading of each position (None past a shorter record)."""
        positions = [self.results[part].positions[k] for k in sorted(self.results[part].positions)]
        length = max((item.n for item in positions), default=0)
        return [
            [float(item.values[i]) if i < item.n else None for item in positions]
            for i in range(length)
        ]


def _attempt(db: Session, session: LabSession, number: int) -> Attempt:
    attempt = db.exec(
        select(Attempt).where(Attempt.session_id == session.id, Attempt.number == number)
    ).first()
    if attempt is None:
        raise UserError("report.no_such_attempt", status=404)
    return attempt


def _number(attempt: Attempt) -> int:
    return attempt.number


def build_report(db: Session, session: LabSession, attempt_number: int | None = None) -> Report:
    """The report of ``session``: attempt ``attempt_number`` as submitted, or, with None,
    the current data and discussion draft -- unless the work can no longer change (graded,
    or an assignment's awaiting review): then its latest attempt, with its review.

    The review (feedback, position comments) appears once the teacher has returned or
    released that attempt, the grade once it is released, and the secret truth under the
    assignment's reveal rule -- the same rules as the student's page, whoever asks."""
    assignment = db.get(Assignment, session.assignment_id) if session.assignment_id else None
    course = db.get(Course, assignment.course_id) if assignment else None
    attempts = db.exec(select(Attempt).where(Attempt.session_id == session.id)).all()
    if attempt_number is not None:
        attempt = _attempt(db, session, attempt_number)
    else:  # work that can no longer change is reported as it was submitted (and graded)
        attempt = None if is_editable(session) else max(attempts, key=_number, default=None)
    selection = Selection(session.id, attempt.id if attempt else None)
    takes = selection.takes(db)
    report = Report(
        session=session,
        assignment=assignment,
        course=course,
        members=members_of(db, session),
        attempt=attempt,
        results=solve_takes(db, session, takes),
        discussion=attempt.discussion if attempt else session.discussion,
        generated_at=utcnow(),
        sources=sorted({take.source for take in takes}),
        preset_name=session.simulator_preset if session.simulator_preset in PRESETS else None,
        take_keys=tuple(sorted((take.id, take.trim_start, take.n_samples) for take in takes)),
    )
    if truth_visible(session, assignment, len(attempts)):
        report.truth = session_truth(db, session, assignment, takes)
        if assignment is not None and attempt is not None:
            report.check = auto_check(json.loads(attempt.results_json), report.truth, assignment)
    if attempt is not None and shown_to_student(attempt):
        report.feedback = attempt.feedback
        report.comments = comments_of(attempt)
        if attempt.released_at is not None:
            report.grade = grade_text(attempt, assignment)
    return report
