"""Lab sessions in the database: takes, results, submissions and exports.

Every number comes from ``app.core``; this module only moves data in and out.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from itertools import pairwise

import numpy as np
from sqlmodel import Session, func, select

from app import __version__
from app.config import get_settings
from app.core.exceptions import UserError
from app.core.explain import explain_heading, explain_latitude
from app.core.jsonsafe import json_safe
from app.core.noise_model import GyroNoise, Window
from app.core.solve import solve_heading, solve_latitude
from app.courses.characterisation import StationNoise, station_noise
from app.lab.samples import chunks, unpack
from app.lab.sim import FIRST_PASS, position_count, preset_for
from app.models import (
    Assignment,
    Attempt,
    InputMethod,
    LabSession,
    LatePolicy,
    Part,
    SampleChunk,
    SessionStatus,
    Take,
    utcnow,
)

PARTS = tuple(Part)
POSITIONS = 8  # the most a part can have: the symmetric order 1-2-3-4-4-3-2-1
MAX_SAMPLES_PER_POSITION = 1_000_000
PLAUSIBLE_RATE_DEG_H = 7200.0  # 2 °/s: a gyro at rest reads Earth's rate plus its bias


@dataclass
class PositionData:
    take: Take
    values: np.ndarray
    times: np.ndarray | None


@dataclass
class PartResult:
    part: str
    positions: dict[int, PositionData]
    result: object | None = None  # HeadingResult | LatitudeResult
    error: UserError | None = None
    steps: list = field(default_factory=list)
    flags: list[dict] = field(default_factory=list)

    def to_json(self) -> dict | None:
        return None if self.result is None else self.result.to_json()


def current_takes(db: Session, session_id: int) -> list[Take]:
    return list(
        db.exec(
            select(Take)
            .where(Take.session_id == session_id, Take.superseded_at.is_(None))
            .order_by(Take.part, Take.position)
        ).all()
    )


def take_history(db: Session, session_id: int) -> list[Take]:
    return list(
        db.exec(
            select(Take).where(Take.session_id == session_id).order_by(Take.created_at, Take.id)
        ).all()
    )


def load_samples(db: Session, take: Take) -> tuple[np.ndarray, np.ndarray | None]:
    rows = db.exec(
        select(SampleChunk).where(SampleChunk.take_id == take.id).order_by(SampleChunk.seq)
    ).all()
    values = np.concatenate([unpack(r.values) for r in rows]) if rows else np.empty(0)
    if rows and all(r.times is not None for r in rows):
        return values, np.concatenate([unpack(r.times) for r in rows])
    return values, None


def check_position(session: LabSession, part: str, position: int) -> None:
    """A position this session's schedule has (5–8 only in the symmetric order)."""
    if part not in PARTS or not 1 <= position <= POSITIONS:
        raise UserError("lab.bad_position", f"There is no position {position}.", position=position)
    if position > position_count(session):
        raise UserError(
            "lab.needs_symmetric",
            f"Position {position} belongs to the symmetric order 1-2-3-4-4-3-2-1; switch it on "
            "first.",
            position=position,
        )


def set_symmetric_order(db: Session, session: LabSession, symmetric: bool) -> None:
    """Switch the recording order.  Switching back is refused while positions 5–8 hold
    readings (they would silently drop out of the result)."""
    if session.status == SessionStatus.graded or (
        session.status == SessionStatus.submitted and session.assignment_id is not None
    ):
        raise UserError("lab.awaiting_review", "This work is waiting for review or graded.")
    if not symmetric and session.symmetric_order:
        in_return_pass = db.exec(
            select(Take.id).where(
                Take.session_id == session.id,
                Take.position > FIRST_PASS,
                Take.superseded_at.is_(None),
            )
        ).first()
        if in_return_pass is not None:
            raise UserError(
                "lab.return_pass_recorded",
                "Positions 5–8 already hold readings; the symmetric order stays on.",
            )
    session.symmetric_order = symmetric
    session.updated_at = utcnow()
    db.add(session)


def store_take(
    db: Session,
    session: LabSession,
    *,
    part: str,
    position: int,
    angle_deg: float,
    values: np.ndarray,
    times: np.ndarray | None,
    source: str,
    unit: str = "deg/h",
    check_minimum: bool = True,
) -> Take:
    """Add a take (values in °/h) and supersede the previous one; the caller commits once,
    so the position is either fully saved or not at all."""
    if session.status == SessionStatus.graded:
        raise UserError("lab.already_graded", "This work has been graded.")
    if session.status == SessionStatus.submitted and session.assignment_id is not None:
        raise UserError(
            "lab.awaiting_review", "Your last attempt is waiting for your teacher's review."
        )
    check_position(session, part, position)
    if values.size == 0:
        raise UserError(
            "readings.empty_position", f"Position {position} has no readings.", position=position
        )
    if values.size > MAX_SAMPLES_PER_POSITION:
        raise UserError(
            "lab.too_many_samples",
            f"At most {MAX_SAMPLES_PER_POSITION} readings per position.",
            limit=MAX_SAMPLES_PER_POSITION,
        )
    _check_values(session, position, values)
    _check_angle_and_times(position, angle_deg, times, values.size)
    _check_storage(db, session, values, times)
    if check_minimum and values.size < session.min_readings:
        raise UserError(
            "lab.too_few_readings",
            f"Position {position} has {values.size} readings; at least "
            f"{session.min_readings} are required.",
            position=position,
            n=int(values.size),
            minimum=session.min_readings,
        )
    now = utcnow()
    for old in db.exec(
        select(Take).where(
            Take.session_id == session.id,
            Take.part == part,
            Take.position == position,
            Take.superseded_at.is_(None),
        )
    ).all():
        old.superseded_at = now
        db.add(old)
    take = Take(
        session_id=session.id,
        part=part,
        position=position,
        angle_deg=angle_deg,
        source=source,
        unit=unit,
        n_samples=int(values.size),
    )
    db.add(take)
    db.flush()
    for seq, value_blob, time_blob in chunks(values, times):
        db.add(SampleChunk(take_id=take.id, seq=seq, values=value_blob, times=time_blob))
    session.updated_at = now
    if session.status in (SessionStatus.submitted, SessionStatus.returned):
        session.status = SessionStatus.in_progress  # an edit after submitting starts a new attempt
    db.add(session)
    return take


def append_samples(
    db: Session,
    session: LabSession,
    *,
    part: str,
    position: int,
    angle_deg: float,
    values: np.ndarray,
    times: np.ndarray | None,
    unit: str = "deg/h",
    offset: int | None = None,
) -> tuple[Take, int]:
    """Append readings (°/h) to the position's current API take, or start one.

    ``offset`` is the index of the first value: values already stored are skipped (a
    retried batch is not duplicated); an offset beyond the stored count is a gap.
    Returns (take, number of values added).
    """
    if session.status == SessionStatus.graded or (
        session.status == SessionStatus.submitted and session.assignment_id is not None
    ):
        raise UserError("lab.awaiting_review", "This work is waiting for review or graded.")
    check_position(session, part, position)
    take = db.exec(
        select(Take).where(
            Take.session_id == session.id,
            Take.part == part,
            Take.position == position,
            Take.superseded_at.is_(None),
            Take.source == InputMethod.api,
        )
    ).first()
    stored = take.n_samples if take is not None else 0
    if offset is not None:
        if offset > stored:
            raise UserError(
                "lab.offset_gap",
                f"Expected offset {stored}, got {offset}: some samples are missing.",
                status=409,
                expected=stored,
            )
        skip = stored - offset
        values = values[skip:]
        times = None if times is None else times[skip:]
    if take is None or not values.size:
        if take is None:
            if not values.size:
                raise UserError("readings.empty_position", "No samples to add.")
            new = store_take(
                db,
                session,
                part=part,
                position=position,
                angle_deg=angle_deg,
                values=values,
                times=times,
                source=InputMethod.api,
                unit=unit,
                check_minimum=False,
            )
            return new, int(values.size)
        return take, 0
    if stored + values.size > MAX_SAMPLES_PER_POSITION:
        raise UserError(
            "lab.too_many_samples",
            f"At most {MAX_SAMPLES_PER_POSITION} readings per position.",
            limit=MAX_SAMPLES_PER_POSITION,
        )
    _check_values(session, position, values)
    _check_angle_and_times(position, angle_deg, times, values.size)
    existing = db.exec(
        select(SampleChunk).where(SampleChunk.take_id == take.id).order_by(SampleChunk.seq)
    ).all()
    has_times = all(chunk.times is not None for chunk in existing)
    if has_times != (times is not None):
        raise UserError(
            "lab.times_mismatch", "Send times with every batch of a position, or with none."
        )
    _check_storage(db, session, values, times, copying=take if take.frozen else None)
    if take.frozen:  # submitted data never changes: continue in a copy of the take
        take, existing = _copy_take(db, take, existing)
    next_seq = max(chunk.seq for chunk in existing) + 1
    for seq, value_blob, time_blob in chunks(values, times):
        db.add(SampleChunk(take_id=take.id, seq=next_seq + seq, values=value_blob, times=time_blob))
    take.n_samples = stored + int(values.size)
    session.updated_at = utcnow()
    if session.status in (SessionStatus.submitted, SessionStatus.returned):
        session.status = SessionStatus.in_progress
    db.add(take)
    db.add(session)
    return take, int(values.size)


def _copy_take(db: Session, take: Take, rows: list[SampleChunk]) -> tuple[Take, list[SampleChunk]]:
    """A new current take with the same samples; ``take`` (frozen) is superseded."""
    now = utcnow()
    copy = Take(
        session_id=take.session_id,
        part=take.part,
        position=take.position,
        angle_deg=take.angle_deg,
        source=take.source,
        unit=take.unit,
        n_samples=take.n_samples,
        created_at=now,
    )
    take.superseded_at = now
    db.add(take)
    db.add(copy)
    db.flush()
    copied = [
        SampleChunk(take_id=copy.id, seq=row.seq, values=row.values, times=row.times)
        for row in rows
    ]
    db.add_all(copied)
    return copy, copied


def storage_used(db: Session, owner_id: int) -> int:
    """Bytes of samples (and times) stored in every take of one student's sessions."""
    size = func.length(SampleChunk.values) + func.coalesce(func.length(SampleChunk.times), 0)
    return int(
        db.exec(
            select(func.coalesce(func.sum(size), 0))
            .join(Take, Take.id == SampleChunk.take_id)
            .join(LabSession, LabSession.id == Take.session_id)
            .where(LabSession.owner_id == owner_id)
        ).one()
    )


def _check_storage(
    db: Session,
    session: LabSession,
    values: np.ndarray,
    times: np.ndarray | None,
    copying: Take | None = None,
) -> None:
    """Refuse a recording that would take the student past their storage quota."""
    limit = get_settings().student_storage_mb * 1024 * 1024
    adding = values.nbytes + (times.nbytes if times is not None else 0)
    if copying is not None:
        adding += copying.n_samples * 16
    if storage_used(db, session.owner_id) + adding > limit:
        raise UserError(
            "lab.storage_full",
            f"Your recordings would use more than your {limit // 2**20} MB of storage. "
            "Ask your teacher to remove old re-recordings.",
            status=413,
            limit_mb=limit // 2**20,
        )


MAX_ANGLE_DEG = 3600.0  # ten turns of the dial: anything beyond is a typing mistake


def _check_angle_and_times(
    position: int, angle_deg: float, times: np.ndarray | None, n_values: int
) -> None:
    if not math.isfinite(angle_deg) or abs(angle_deg) > MAX_ANGLE_DEG:
        raise UserError(
            "lab.bad_angle",
            f"The angle of position {position} must be a finite number of degrees "
            f"(at most ±{MAX_ANGLE_DEG:g}).",
            position=position,
            limit=MAX_ANGLE_DEG,
        )
    if times is not None and (times.size != n_values or not np.all(np.isfinite(times))):
        raise UserError(
            "lab.bad_times",
            f"Position {position}: give one finite time per reading.",
            position=position,
        )


def _check_values(session: LabSession, position: int, values: np.ndarray) -> None:
    if not np.all(np.isfinite(values)):
        raise UserError(
            "readings.not_finite", "A reading is not a finite number.", position=position
        )
    if values.size and float(np.max(np.abs(values))) > PLAUSIBLE_RATE_DEG_H:
        raise UserError(
            "lab.implausible_rate",
            f"Position {position} has readings above {PLAUSIBLE_RATE_DEG_H:g} °/h, far more than "
            "a gyro at rest can read: check the unit.",
            position=position,
        )


SessionData = dict[str, dict[int, PositionData]]  # part → position → data


def _assemble(take: Take, rows: list[SampleChunk]) -> PositionData:
    values = np.concatenate([unpack(r.values) for r in rows]) if rows else np.empty(0)
    times = None
    if rows and all(r.times is not None for r in rows):
        times = np.concatenate([unpack(r.times) for r in rows])
    return PositionData(take, values, times)


def iter_current_data(db: Session, *where) -> Iterator[tuple[int, SessionData]]:
    """(session id, its current data) for the sessions matching ``where`` (conditions on
    LabSession), in one query whatever the number of sessions -- one statement, so it sees
    one consistent snapshot even under PostgreSQL's READ COMMITTED while students save.
    Rows are streamed in order, so only one session's samples are in memory at a time.
    (Every take has at least one chunk: ``store_take`` writes one even for no samples.)"""
    rows = db.exec(
        select(Take, SampleChunk)
        .join(SampleChunk, SampleChunk.take_id == Take.id)
        .join(LabSession, LabSession.id == Take.session_id)
        .where(Take.superseded_at.is_(None), *where)
        .order_by(Take.session_id, Take.part, Take.position, SampleChunk.seq)
        .execution_options(yield_per=64)
    )
    session_id: int | None = None
    data: SessionData = {}
    take: Take | None = None
    pending: list[SampleChunk] = []
    for row_take, chunk in rows:
        if take is not None and row_take.id != take.id:
            data.setdefault(take.part, {})[take.position] = _assemble(take, pending)
            pending = []
            if row_take.session_id != session_id:
                yield session_id, data
                data = {}
        take, session_id = row_take, row_take.session_id
        pending.append(chunk)
    if take is not None:
        data.setdefault(take.part, {})[take.position] = _assemble(take, pending)
        yield session_id, data


def current_data(db: Session, session: LabSession) -> SessionData:
    """All current positions of one session with their samples (two queries)."""
    return dict(iter_current_data(db, LabSession.id == session.id)).get(session.id, {})


def simulated_noise(session: LabSession, ordered: list[PositionData]) -> dict:
    """When every position was recorded from the simulated gyro its noise model is known:
    the position means' covariance and the table's indexing σ, for the solver.  Recordings
    on the session's one gyro timeline (sample times in gyro seconds, not overlapping) are
    correlated through the slow bias and the random walk; recordings made before the
    timeline existed are separate runs.  Otherwise nothing (the σ assumes white noise)."""
    if not ordered or any(p.take.source != InputMethod.simulator for p in ordered):
        return {}
    preset = preset_for(session)
    noise = GyroNoise.from_preset(preset)
    length = [p.values.size / preset.sample_rate_hz for p in ordered]
    windows = [
        Window(float(p.times[0]) if p.times is not None and p.times.size else 0.0, span)
        for p, span in zip(ordered, length, strict=True)
    ]
    spans = sorted((w.start_s, w.end_s) for w in windows)
    on_one_clock = all(end <= start + 1e-6 for (_, end), (start, _) in pairwise(spans))
    if not on_one_clock:
        windows = [Window(0.0, span) for span in length]
    return {
        "position_cov": noise.mean_covariance(windows, continuous=on_one_clock),
        "indexing_sigma_deg": noise.indexing_sigma_deg,
    }


def characterised_noise(station: StationNoise | None, ordered: list[PositionData]) -> dict:
    """Readings from a real gyro the teacher characterised (typed, CSV, API, bridge): each
    position mean's variance from its noise model over the position's recording, taken as
    separate recordings (their timing on the bench is not known)."""
    if (
        station is None
        or not ordered
        or any(p.take.source == InputMethod.simulator for p in ordered)
    ):
        return {}
    windows = [Window(0.0, p.values.size / station.rate_hz) for p in ordered]
    return {"position_cov": station.noise.mean_covariance(windows, continuous=False)}


def station_noise_for(db: Session, session: LabSession) -> StationNoise | None:
    if session.assignment_id is None:
        return None
    return station_noise(db.get(Assignment, session.assignment_id))


def solve_part(
    session: LabSession,
    part: str,
    data: dict[int, PositionData],
    station: StationNoise | None = None,
) -> PartResult:
    outcome = PartResult(part, data)
    if len(data) < 3:
        outcome.error = UserError(
            "lab.need_positions",
            "Record at least 3 positions to compute a result.",
            recorded=len(data),
        )
        return outcome
    ordered = [data[k] for k in sorted(data)]
    values = [p.values for p in ordered]
    angles = [p.take.angle_deg for p in ordered]
    known = simulated_noise(session, ordered) or characterised_noise(station, ordered)
    if len(ordered) > FIRST_PASS and all(p.times is not None for p in ordered):
        # the symmetric order, timed on one clock: the fit adds b + ḃ·(t − t̄)
        known["times_s"] = [p.times for p in ordered]
    try:
        if part == "heading":
            outcome.result = solve_heading(values, angles, **known)
            outcome.steps = explain_heading(outcome.result)
        else:
            outcome.result = solve_latitude(
                values,
                angles,
                true_latitude_deg=session.latitude_deg,
                true_earth_rate_deg_h=session.earth_rate_deg_h,
                **known,
            )
            outcome.steps = explain_latitude(outcome.result)
    except UserError as error:
        outcome.error = error
    outcome.flags = quality_flags(session, data)
    if outcome.result is not None and outcome.result.fit.closure_consistent is False:
        fit = outcome.result.fit
        outcome.flags.append(
            {
                "key": "flag.closure",
                "params": {"d": f"{fit.closure_residual:.3f}", "sigma": f"{fit.closure_sigma:.3f}"},
            }
        )
    return outcome


def quality_flags(session: LabSession, data: dict[int, PositionData]) -> list[dict]:
    """Data-quality warnings: too few readings, spikes, a position far noisier than the rest.

    Each flag is ``{"key": message key, "params": {...}}``.
    """

    def flag(key: str, **params) -> dict:
        return {"key": key, "params": params}

    flags = []
    stds = {}
    for position, item in sorted(data.items()):
        if item.values.size < session.min_readings:
            flags.append(
                flag(
                    "flag.too_few",
                    position=position,
                    n=int(item.values.size),
                    minimum=session.min_readings,
                )
            )
        if item.values.size >= 2:
            stds[position] = float(item.values.std(ddof=1))
            median = float(np.median(item.values))
            mad = float(np.median(np.abs(item.values - median))) * 1.4826
            outliers = int(np.sum(np.abs(item.values - median) > 6 * mad)) if mad > 0 else 0
            if outliers:
                flags.append(flag("flag.spikes", position=position, n=outliers))
    if len(stds) >= 3:
        typical = float(np.median(list(stds.values())))
        for position, std in stds.items():
            if typical > 0 and std > 3 * typical:
                flags.append(flag("flag.noisy", position=position, ratio=round(std / typical, 1)))
    return flags


def session_results(db: Session, session: LabSession) -> dict[str, PartResult]:
    data = current_data(db, session)
    station = station_noise_for(db, session)
    return {part: solve_part(session, part, data.get(part, {}), station) for part in PARTS}


def results_json(results: dict[str, PartResult]) -> dict:
    return {part: outcome.to_json() for part, outcome in results.items()}


def submit(db: Session, session: LabSession) -> Attempt:
    """Freeze the current data and results as a new attempt.

    An assignment's rules apply: no new attempt while the last one awaits review or after
    grading, at most ``max_attempts``, and after the due date either refused or flagged late.
    """
    assignment = db.get(Assignment, session.assignment_id) if session.assignment_id else None
    previous = db.exec(select(Attempt).where(Attempt.session_id == session.id)).all()
    if session.status == SessionStatus.graded:
        raise UserError("lab.already_graded", "This work has been graded.", status=409)
    if assignment is not None and session.status == SessionStatus.submitted:
        raise UserError(
            "lab.awaiting_review",
            "Your last attempt is waiting for your teacher's review.",
            status=409,
        )
    if (
        assignment is not None
        and assignment.max_attempts
        and len(previous) >= assignment.max_attempts
    ):
        raise UserError(
            "lab.no_attempts_left",
            f"All {assignment.max_attempts} attempts are used.",
            status=409,
            limit=assignment.max_attempts,
        )
    now = utcnow()
    late = bool(assignment and assignment.due_at and now > assignment.due_at)
    if late and assignment.late_policy == LatePolicy.refuse:
        raise UserError(
            "lab.past_due", "The due date has passed; submissions are closed.", status=409
        )
    results = session_results(db, session)
    if all(outcome.result is None for outcome in results.values()):
        raise UserError(
            "lab.nothing_to_submit", "There is no result to submit yet: record the positions first."
        )
    takes = current_takes(db, session.id)
    for take in takes:  # an attempt's takes never change again (appends copy them)
        take.frozen = True
        db.add(take)
    attempt = Attempt(
        session_id=session.id,
        number=len(previous) + 1,
        take_ids=",".join(str(t.id) for t in takes),
        results_json=json.dumps(json_safe(results_json(results))),
        submitted_at=now,
        late=late,
    )
    session.status = SessionStatus.submitted
    session.updated_at = utcnow()
    db.add(attempt)
    db.add(session)
    return attempt


def export_metadata(session: LabSession) -> dict:
    """What a teacher or a script needs to know about a session (never the secret truth)."""
    return {
        "software": f"GyroLab {__version__}",
        "session_id": session.id,
        "title": session.title,
        "assignment_id": session.assignment_id,
        "station": {
            "latitude_deg": session.latitude_deg,
            "earth_rate_deg_h": session.earth_rate_deg_h,
        },
        "heading": {
            "rotation": session.heading_rotation,
            "start_angle_deg": session.heading_start_deg,
        },
        "latitude": {
            "start_angle_deg": session.latitude_start_deg,
            "step_deg": session.latitude_step_deg,
        },
        "simulator_preset": session.simulator_preset,
        "status": session.status,
        "exported_at": utcnow().isoformat(),
    }
