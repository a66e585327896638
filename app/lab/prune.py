"""Remove old re-recordings: takes that were superseded long ago and that no submitted
attempt refers to (an attempt's takes are frozen and never removed)."""

from __future__ import annotations

from dataclasses import dataclass
from datetime import timedelta

from sqlalchemy import delete, func
from sqlmodel import Session, select

from app.lab.quota import stored_bytes
from app.models import SampleChunk, Take, utcnow


@dataclass
class Pruned:
    takes: int
    bytes: int


def prune_takes(db: Session, older_than_days: int) -> Pruned:
    """Delete superseded, never-submitted takes superseded more than ``older_than_days``
    ago, with their samples (the caller commits)."""
    cutoff = utcnow() - timedelta(days=older_than_days)
    doomed = (
        select(Take.id)
        .where(
            Take.superseded_at.is_not(None),
            Take.superseded_at < cutoff,
            Take.frozen.is_(False),
        )
        .scalar_subquery()
    )
    size = stored_bytes()
    freed = db.exec(
        select(func.coalesce(func.sum(size), 0)).where(SampleChunk.take_id.in_(doomed))
    ).one()
    db.exec(delete(SampleChunk).where(SampleChunk.take_id.in_(doomed)))
    removed = db.exec(
        delete(Take).where(
            Take.superseded_at.is_not(None), Take.superseded_at < cutoff, Take.frozen.is_(False)
        )
    ).rowcount
    return Pruned(int(removed or 0), int(freed))
