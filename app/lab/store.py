"""A lab session's recordings in the database: takes (one per recording of a position,
never deleted, superseded by a re-recording), their samples, and the checks on them (the
readings' own checks: ``lab.reading_checks``).

Every number comes from ``app.core``; this module only moves data in and out.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from sqlalchemy import bindparam, func, insert, update
from sqlmodel import Session, select

from app.core.exceptions import UserError
from app.lab.quota import check_storage
from app.lab.reading_checks import check_angle_and_times, check_temperatures, check_values
from app.lab.recent_samples import hold
from app.lab.samples import chunks, unpack
from app.lab.sim import FIRST_PASS, position_count
from app.models import (
    LabSession,
    Part,
    SampleChunk,
    SessionStatus,
    Take,
    utcnow,
)

PARTS = tuple(Part)
POSITIONS = 8  # the most a part can have: the symmetric order 1-2-3-4-4-3-2-1
MAX_SAMPLES_PER_POSITION = 1_000_000


# The hot paths' statements are built once with bound parameters (``params=``): building
# a select and its cache key on every call cost more than running it on SQLite.
CURRENT_TAKES = (
    select(Take)
    .where(Take.session_id == bindparam("session_id"), Take.superseded_at.is_(None))
    .order_by(Take.part, Take.position)
)


def current_takes(db: Session, session_id: int) -> list[Take]:
    return list(db.exec(CURRENT_TAKES, params={"session_id": session_id}).all())


HISTORY_ROWS = 50  # the recording history a page shows: the most recent ones


def take_history(db: Session, session_id: int, limit: int = HISTORY_ROWS) -> tuple[list[Take], int]:
    """The session's ``limit`` most recent takes, newest first, and how many it has in
    all (one query: a student who re-records a position 200 times has 800 takes, and the
    page listed every one of them, 30 ms of rendering)."""
    rows = db.exec(TAKE_HISTORY, params={"session_id": session_id, "limit": limit}).all()
    return [take for take, _ in rows], (rows[0][1] if rows else 0)


TAKE_HISTORY = (
    select(Take, func.count().over())
    .where(Take.session_id == bindparam("session_id"))
    .order_by(Take.created_at.desc(), Take.id.desc())
    .limit(bindparam("limit"))
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
        raise UserError("lab.bad_position", position=position)
    if position > position_count(session):
        raise UserError(
            "lab.needs_symmetric",
            position=position,
        )


def set_symmetric_order(db: Session, session: LabSession, symmetric: bool) -> None:
    """Switch the recording order.  Switching back is refused while positions 5–8 hold
    readings (they would silently drop out of the result)."""
    check_editable(session)
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
            )
    session.symmetric_order = symmetric
    session.updated_at = utcnow()
    db.add(session)


def check_editable(session: LabSession) -> None:
    """Graded work and work awaiting review do not change (409: the state forbids it).

    The one check of every change to a session's data -- a take stored, appended or
    trimmed, the order or plane chosen, the discussion written -- and of submitting again.
    """
    if session.status == SessionStatus.graded:
        raise UserError("lab.already_graded", status=409)
    if session.status == SessionStatus.submitted and session.assignment_id is not None:
        raise UserError("lab.awaiting_review", status=409)


def is_editable(session: LabSession) -> bool:
    """Whether the student may still record (:func:`check_editable` would let them)."""
    try:
        check_editable(session)
    except UserError:
        return False
    return True


def reopen(session: LabSession) -> None:
    """An edit after submitting (or after the work came back) starts the next attempt."""
    session.updated_at = utcnow()
    if session.status in (SessionStatus.submitted, SessionStatus.returned):
        session.status = SessionStatus.in_progress


@dataclass(frozen=True)
class NewTake:
    """One position's readings to store: values in °/h, optional times (s) and case
    temperatures (°C), and the dial angle."""

    position: int
    angle_deg: float
    values: np.ndarray
    times: np.ndarray | None = None
    temperatures: np.ndarray | None = None


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
    temperatures: np.ndarray | None = None,
) -> Take:
    """Add a take (values in °/h) and supersede the previous one (:func:`store_takes`)."""
    new = NewTake(position, angle_deg, values, times, temperatures)
    return store_takes(
        db, session, part=part, takes=[new], source=source, unit=unit, check_minimum=check_minimum
    )[0]


def store_takes(
    db: Session,
    session: LabSession,
    *,
    part: str,
    takes: list[NewTake],
    source: str,
    unit: str = "deg/h",
    check_minimum: bool = True,
) -> list[Take]:
    """Add a take for each of ``takes`` (positions of one part) and supersede the previous
    ones; the caller commits once, so the positions are either all saved or none.

    Every position is checked, in order, before anything is written; then one statement
    supersedes the previous takes, one inserts the new ones and one their samples (the
    write lock is held for a few statements, not a few per position: under load each is a
    wait for the interpreter, bench/README.md)."""
    check_editable(session)
    positions = [new.position for new in takes]
    if not positions:
        raise UserError("readings.none")
    if len(set(positions)) != len(positions):
        raise ValueError("store_takes: one take per position")
    for new in takes:
        _check_new_take(db, session, part, new, check_minimum)
    db.exec(
        update(Take)
        .where(
            Take.session_id == session.id,
            Take.part == part,
            Take.position.in_(positions),
            Take.superseded_at.is_(None),
        )
        .values(superseded_at=utcnow())
    )
    fields = [
        {
            "session_id": session.id,
            "part": part,
            "position": new.position,
            "angle_deg": new.angle_deg,
            "source": source,
            "unit": unit,
            "n_samples": int(new.values.size),
        }
        for new in takes
    ]
    # one INSERT … RETURNING for all; the rows come back in no promised order, so each is
    # matched to its position
    inserted = {take.position: take for take in db.scalars(INSERT_TAKES, fields)}
    rows = [inserted[position] for position in positions]
    blocks = []
    for take, new in zip(rows, takes, strict=True):
        hold(db, take, new.values, new.times, new.temperatures)
        blocks += [
            {"take_id": take.id, "seq": seq, "values": value_blob, "times": time_blob,
             "temperatures": temperature_blob}
            for seq, value_blob, time_blob, temperature_blob in chunks(
                new.values, new.times, new.temperatures
            )
        ]  # fmt: skip
    # one executemany of a statement compiled once (a multi-row VALUES is compiled anew
    # for every save)
    db.execute(INSERT_CHUNKS, blocks)
    reopen(session)
    db.add(session)
    return rows


INSERT_TAKES = insert(Take).returning(Take)  # built once, as the selects above
INSERT_CHUNKS = insert(SampleChunk)


def _check_new_take(
    db: Session, session: LabSession, part: str, new: NewTake, check_minimum: bool
) -> None:
    """A position's readings checked before they are stored (the storage quota counted)."""
    position, values = new.position, new.values
    check_position(session, part, position)
    if values.size == 0:
        raise UserError("readings.empty_position", position=position)
    if values.size > MAX_SAMPLES_PER_POSITION:
        raise UserError(
            "lab.too_many_samples",
            limit=MAX_SAMPLES_PER_POSITION,
        )
    check_values(session, position, values)
    check_angle_and_times(position, new.angle_deg, new.times, values.size)
    check_temperatures(position, new.temperatures, values.size)
    check_storage(db, session, values, new.times, new.temperatures)
    if check_minimum and values.size < session.min_readings:
        raise UserError(
            "lab.too_few_readings",
            position=position,
            n=int(values.size),
            minimum=session.min_readings,
        )


def copy_take(db: Session, take: Take) -> Take:
    """A frozen (submitted) take's samples in a new current take, to change its metadata."""
    rows = db.exec(
        select(SampleChunk).where(SampleChunk.take_id == take.id).order_by(SampleChunk.seq)
    ).all()
    return copy_take_and_chunks(db, take, rows)[0]


def copy_take_and_chunks(
    db: Session, take: Take, rows: list[SampleChunk]
) -> tuple[Take, list[SampleChunk]]:
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
        trim_start=take.trim_start,
        created_at=now,
    )
    take.superseded_at = now
    db.add(take)
    db.add(copy)
    db.flush()
    copied = [
        SampleChunk(
            take_id=copy.id,
            seq=row.seq,
            values=row.values,
            times=row.times,
            temperatures=row.temperatures,
        )
        for row in rows
    ]
    db.add_all(copied)
    return copy, copied
