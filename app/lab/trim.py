"""Trimming the start of a recording: the transient after turning the table.  The trim is
stored on the take (``trim_start``); no sample is ever deleted, and a submitted take is
copied first, so what an attempt holds never changes."""

from __future__ import annotations

from sqlmodel import Session, select

from app.core.exceptions import UserError
from app.lab.store import check_editable, check_position, copy_take, reopen
from app.models import LabSession, Take


def current_take(db: Session, session: LabSession, part: str, position: int) -> Take:
    check_position(session, part, position)
    take = db.exec(
        select(Take).where(
            Take.session_id == session.id,
            Take.part == part,
            Take.position == position,
            Take.superseded_at.is_(None),
        )
    ).first()
    if take is None:
        raise UserError("lab.nothing_to_trim", position=position)
    return take


def trim_position(db: Session, session: LabSession, *, part: str, position: int, trim: int) -> Take:
    """Leave out the first ``trim`` readings of a position (0 restores them all).

    At least the session's minimum number of readings must remain.  The caller commits.
    """
    check_editable(session)
    take = current_take(db, session, part, position)
    if not 0 <= trim < take.n_samples:
        raise UserError(
            "lab.bad_trim",
            high=max(take.n_samples - 1, 0),
        )
    left = take.n_samples - trim
    if trim and left < session.min_readings:
        raise UserError(
            "lab.trim_too_much",
            left=left,
            minimum=session.min_readings,
        )
    if trim == (take.trim_start or 0):
        return take
    if take.frozen:  # submitted: the attempt keeps its take; the change goes to a copy
        take = copy_take(db, take)
    take.trim_start = trim
    reopen(session)
    db.add(take)
    db.add(session)
    return take
