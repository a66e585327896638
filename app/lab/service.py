"""Recording a lab session: the one path shared by the pages, the REST API and the stream.

Who may record how (:func:`recordable_session`), and how readings become a stored take
(:func:`record_position`, :func:`record_positions`, :func:`append_readings`): the unit
converted to °/h, the dial angle defaulting to the session's schedule, the position checked
against the schedule (4, or 8 in the symmetric order).  The caller commits once, so a
position is saved whole or not at all.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from sqlmodel import Session, select

from app.core.exceptions import UserError
from app.core.units import canonical_unit, to_deg_per_hour
from app.db import lock_rows, locks_rows
from app.lab.partners import is_member
from app.lab.sim import nominal_angle
from app.lab.store import NewTake, check_position, store_takes
from app.lab.take_appends import append_samples
from app.models import Assignment, InputMethod, LabSession, Take, User


def allowed_methods(db: Session, session: LabSession) -> list[str]:
    """What the session's assignment allows (a practice session: everything)."""
    if session.assignment_id is None:
        return [InputMethod.manual, InputMethod.csv, InputMethod.simulator]
    assignment = db.get(Assignment, session.assignment_id)
    return list(assignment.methods) if assignment else []


def own_session(db: Session, user: User, session_id: int) -> LabSession:
    """The user's own session, or one they share as a lab partner; anyone else's (or none)
    answers 404.  In a row writer's transaction the session's row and its owner's are
    locked first (``db.lock_rows``: offsets, attempt numbers and the storage quota are
    read-check-writes), so writes to one session queue and others' proceed."""
    if locks_rows(db):  # the usual case, the owner's own session: read as locked, at once
        session = locked_session(db, session_id, owner_id=user.id)
        if session is not None:
            return session
    session = db.get(LabSession, session_id)
    if session is None or not is_member(db, session, user):
        raise UserError("lab.no_such_session", status=404)
    if lock_rows(db, LabSession, session.id):
        lock_rows(db, User, session.owner_id)
        db.refresh(session)  # as of the lock: an earlier writer may just have changed it
    return session


def locked_session(db: Session, session_id: int, owner_id: int | None = None) -> LabSession | None:
    """In a row writer's transaction on PostgreSQL: the session (of ``owner_id``, when
    given) read as it is once locked (``SELECT … FOR UPDATE``), then its owner's row locked
    -- two statements where a read, two locks and a re-read took four.  Elsewhere the
    session as read (SQLite's single writer needs no locks).  None: no such session."""
    if not locks_rows(db):
        session = db.get(LabSession, session_id)
        return session if session is None or owner_id in (None, session.owner_id) else None
    query = select(LabSession).where(LabSession.id == session_id)
    if owner_id is not None:
        query = query.where(LabSession.owner_id == owner_id)
    session = db.exec(query.with_for_update().execution_options(populate_existing=True)).first()
    if session is not None:
        lock_rows(db, User, session.owner_id)
    return session


def require_method(db: Session, session: LabSession, method: InputMethod) -> None:
    allowed = allowed_methods(db, session)
    permitted = (
        bool({InputMethod.manual, InputMethod.csv} & set(allowed))
        if method == InputMethod.api
        else method in allowed
    )
    if not permitted:
        key = "lab.uploads_not_allowed" if method == InputMethod.api else "lab.method_not_allowed"
        raise UserError(key, status=403)


def recordable_session(db: Session, user: User, session_id: int, method: InputMethod) -> LabSession:
    """The user's own session, when its assignment allows recording this way."""
    session = own_session(db, user, session_id)
    require_method(db, session, method)
    return session


@dataclass(frozen=True)
class Reading:
    """Readings as stored: in °/h, with the unit they came in and the dial angle (the
    session's schedule unless given)."""

    values: np.ndarray
    unit: str
    angle_deg: float

    @classmethod
    def of(cls, session, part, position, values, unit, angle_deg) -> Reading:
        unit = canonical_unit(unit)
        angle = nominal_angle(session, part, position) if angle_deg is None else angle_deg
        return cls(to_deg_per_hour(np.asarray(values, dtype=float), unit), unit, float(angle))


def record_position(
    db: Session,
    session: LabSession,
    *,
    part: str,
    position: int,
    values: np.ndarray,
    source: str,
    unit: str = "deg/h",
    times: np.ndarray | None = None,
    angle_deg: float | None = None,
    temperatures: np.ndarray | None = None,
) -> Take:
    """Store one position's readings (in ``unit``) as a new take, replacing the last."""
    new = _new_take(session, part, position, values, unit, angle_deg, times, temperatures)
    return store_takes(
        db, session, part=part, takes=[new], source=source, unit=canonical_unit(unit)
    )[0]


def record_positions(
    db: Session,
    session: LabSession,
    *,
    part: str,
    unit: str,
    columns: dict[int, np.ndarray],
    source: str,
    angles: dict[int, float] | None = None,
    times: dict[int, np.ndarray] | None = None,
    temperatures: dict[int, np.ndarray] | None = None,
) -> list[int]:
    """Store several positions at once (a grid or a file); returns the positions saved."""
    angles, times, temperatures = angles or {}, times or {}, temperatures or {}
    takes = [
        _new_take(
            session,
            part,
            position,
            values,
            unit,
            angles.get(position),
            times.get(position),
            temperatures.get(position),
        )
        for position, values in sorted(columns.items())
    ]
    store_takes(db, session, part=part, takes=takes, source=source, unit=canonical_unit(unit))
    return sorted(columns)


def _new_take(
    session, part, position, values, unit, angle_deg, times=None, temperatures=None
) -> NewTake:
    """One position's readings in °/h at their dial angle, its number checked first."""
    check_position(session, part, position)
    reading = Reading.of(session, part, position, values, unit, angle_deg)
    return NewTake(position, reading.angle_deg, reading.values, times, temperatures)


def append_readings(
    db: Session,
    session: LabSession,
    *,
    part: str,
    position: int,
    values: np.ndarray,
    unit: str = "deg/h",
    times: np.ndarray | None = None,
    angle_deg: float | None = None,
    offset: int | None = None,
    temperatures: np.ndarray | None = None,
) -> tuple[Take, int]:
    """Append readings to a position's API take (a streaming device); returns the take and
    how many samples were new (a retried batch with ``offset`` is stored once)."""
    reading = Reading.of(session, part, position, values, unit, angle_deg)
    return append_samples(
        db,
        session,
        part=part,
        position=position,
        angle_deg=reading.angle_deg,
        values=reading.values,
        times=times,
        unit=reading.unit,
        offset=offset,
        temperatures=temperatures,
    )
