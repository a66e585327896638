"""A student's storage quota: the bytes their recordings hold, and the check before a
recording is stored."""

from __future__ import annotations

import numpy as np
from sqlalchemy import bindparam
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


# Built once: the statement is the same for every student (the owner is a bound parameter).
STORAGE_USED = (
    select(func.coalesce(func.sum(stored_bytes()), 0))
    .join(Take, Take.id == SampleChunk.take_id)
    .join(LabSession, LabSession.id == Take.session_id)
    .where(LabSession.owner_id == bindparam("owner_id"))
)
# db.info key: (the transaction, the owner, bytes used) -- see check_storage
_USED_IN_TRANSACTION = "gyrolab.storage_used"


def storage_used(db: Session, owner_id: int) -> int:
    """Bytes of samples (and times, temperatures) in every take of one student's sessions."""
    return int(db.exec(STORAGE_USED, params={"owner_id": owner_id}).one())


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
    used = _used_in_transaction(db, session.owner_id)
    if used + adding > limit:
        raise UserError(
            "lab.storage_full",
            status=413,
            limit_mb=limit // 2**20,
        )
    db.info[_USED_IN_TRANSACTION] = (db.get_transaction(), session.owner_id, used + adding)


def _used_in_transaction(db: Session, owner_id: int) -> int:
    """The owner's bytes used, queried once per transaction: the recordings stored since
    in the same transaction are added by :func:`check_storage` (a grid or a file stores
    several positions; the owner's row is locked, or SQLite's one writer holds the lock,
    so nothing else adds to it meanwhile)."""
    known = db.info.get(_USED_IN_TRANSACTION)
    transaction = db.get_transaction()
    if known is not None and transaction is not None and known[:2] == (transaction, owner_id):
        return known[2]
    return storage_used(db, owner_id)
