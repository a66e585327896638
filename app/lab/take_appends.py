"""Readings appended to a position's current API take (a device or script sending a
recording in batches): retried batches not duplicated, a gap refused, a submitted take
continued in a copy."""

from __future__ import annotations

import numpy as np
from sqlmodel import Session, select

from app.core.exceptions import UserError
from app.lab.quota import check_storage
from app.lab.reading_checks import (
    check_angle_and_times,
    check_temperatures,
    check_times_follow,
    check_values,
)
from app.lab.samples import chunks, unpack
from app.lab.store import (
    MAX_SAMPLES_PER_POSITION,
    check_editable,
    check_position,
    copy_take_and_chunks,
    reopen,
    store_take,
)
from app.models import InputMethod, LabSession, SampleChunk, Take


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
    temperatures: np.ndarray | None = None,
) -> tuple[Take, int]:
    """Append readings (°/h) to the position's current API take, or start one.

    ``offset`` is the index of the first value: values already stored are skipped (a
    retried batch is not duplicated); an offset beyond the stored count is a gap.
    Returns (take, number of values added).
    """
    check_editable(session)
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
                status=409,
                expected=stored,
            )
        skip = stored - offset
        values = values[skip:]
        times = None if times is None else times[skip:]
        temperatures = None if temperatures is None else temperatures[skip:]
    if take is None or not values.size:
        if take is None:
            if not values.size:
                raise UserError("readings.empty_position", position=position)
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
                temperatures=temperatures,
            )
            return new, int(values.size)
        return take, 0
    if stored + values.size > MAX_SAMPLES_PER_POSITION:
        raise UserError(
            "lab.too_many_samples",
            limit=MAX_SAMPLES_PER_POSITION,
        )
    check_values(session, position, values)
    check_angle_and_times(position, angle_deg, times, values.size, first_reading=stored + 1)
    check_temperatures(position, temperatures, values.size)
    existing = db.exec(
        select(SampleChunk).where(SampleChunk.take_id == take.id).order_by(SampleChunk.seq)
    ).all()
    has_times = all(chunk.times is not None for chunk in existing)
    if has_times != (times is not None):
        raise UserError("lab.times_mismatch")
    if times is not None:
        last_times = unpack(existing[-1].times) if existing else np.empty(0)
        check_times_follow(position, float(last_times[-1]) if last_times.size else None, times)
    has_temperatures = all(chunk.temperatures is not None for chunk in existing)
    if has_temperatures != (temperatures is not None):
        raise UserError(
            "lab.temperatures_mismatch",
        )
    check_storage(db, session, values, times, temperatures, copying=take if take.frozen else None)
    if take.frozen:  # submitted data never changes: continue in a copy of the take
        take, existing = copy_take_and_chunks(db, take, existing)
    next_seq = max(chunk.seq for chunk in existing) + 1
    for seq, value_blob, time_blob, temperature_blob in chunks(values, times, temperatures):
        db.add(
            SampleChunk(
                take_id=take.id,
                seq=next_seq + seq,
                values=value_blob,
                times=time_blob,
                temperatures=temperature_blob,
            )
        )
    take.n_samples = stored + int(values.size)
    reopen(session)
    db.add(take)
    db.add(session)
    return take, int(values.size)
