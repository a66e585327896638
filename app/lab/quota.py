"""A student's storage quota: the bytes their recordings hold, and the check before a
recording is stored."""

from __future__ import annotations

import numpy as np
from sqlmodel import Session, func, select

from app.config import get_settings
from app.core.exceptions import UserError
from app.models import LabSession, SampleChunk, Take


def stored_bytes():
    """SQL: one chunk's bytes (samples, times, temperatures)."""
    return (
        func.length(SampleChunk.values)
        + func.coalesce(func.length(SampleChunk.times), 0)
        + func.coalesce(func.length(SampleChunk.temperatures), 0)
    )


def storage_used(db: Session, owner_id: int) -> int:
    """Bytes of samples (and times, temperatures) in every take of one student's sessions."""
    size = stored_bytes()
    return int(
        db.exec(
            select(func.coalesce(func.sum(size), 0))
            .join(Take, Take.id == SampleChunk.take_id)
            .join(LabSession, LabSession.id == Take.session_id)
            .where(LabSession.owner_id == owner_id)
        ).one()
    )


def check_storage(
    db: Session,
    session: LabSession,
    values: np.ndarray,
    times: np.ndarray | None,
    temperatures: np.ndarray | None = None,
    copying: Take | None = None,
) -> None:
    """Refuse a recording that would take the student past their storage quota."""
    limit = get_settings().student_storage_mb * 1024 * 1024
    adding = sum(a.nbytes for a in (values, times, temperatures) if a is not None)
    if copying is not None:
        adding += copying.n_samples * (8 * (1 + (times is not None) + (temperatures is not None)))
    if storage_used(db, session.owner_id) + adding > limit:
        raise UserError(
            "lab.storage_full",
            f"Your recordings would use more than your {limit // 2**20} MB of storage. "
            "Ask your teacher to remove old re-recordings.",
            status=413,
            limit_mb=limit // 2**20,
        )
