"""Copy keys of submitted attempts, kept in ``copy_key``: so that readings copied from
another group's earlier attempt, or from another year's class, are found after the data
they were copied from has been replaced or the class has ended.

A key is an offset-free pattern of a part's readings (``app.core.data_copies``); only
parts the students recorded themselves (typed, pasted, uploaded, sent by the bridge) have
keys -- the simulated gyro's readings are the server's.  An attempt is indexed when it is
submitted; attempts from before the index existed are indexed when the app starts."""

from __future__ import annotations

import numpy as np
from sqlmodel import Session, select

from app.core.data_copies import copy_keys
from app.db import write_session
from app.lab.results import PositionData, SessionData, takes_data
from app.models import Attempt, CopyKey, InputMethod, Take

MIN_OWN_POSITIONS = 3  # a part with fewer positions of its own readings has no evidence
BACKFILL_BATCH = 200


def own_positions(positions: dict[int, PositionData]) -> list[PositionData]:
    """A part's positions (in order) the students recorded themselves; empty below three."""
    own = [
        positions[k] for k in sorted(positions) if positions[k].take.source != InputMethod.simulator
    ]
    return own if len(own) >= MIN_OWN_POSITIONS else []


def part_keys(data: SessionData) -> dict[str, list[str]]:
    """part → the copy keys of its own readings (parts without keys left out)."""
    out = {}
    for part, positions in sorted(data.items()):
        own = own_positions(positions)
        keys = copy_keys([np.asarray(item.values, float) for item in own]) if own else []
        if keys:
            out[part] = keys
    return out


def keyable_takes(takes: list[Take]) -> list[Take]:
    """The takes whose readings can have copy keys (:func:`own_positions`' rule, decided
    before any sample is read): a part's own takes when it has at least three."""
    own: dict[str, list[Take]] = {}
    for take in takes:
        if take.source != InputMethod.simulator:
            own.setdefault(take.part, []).append(take)
    return [take for group in own.values() if len(group) >= MIN_OWN_POSITIONS for take in group]


def index_attempt(db: Session, attempt: Attempt, takes: list[Take]) -> None:
    """Keep the copy keys of ``attempt``'s takes (``attempt`` must have its id); only the
    samples that can have keys are read (none for a session streamed from the simulator)."""
    data = takes_data(db, keyable_takes(takes))
    for part, keys in part_keys(data).items():
        for key in keys:
            db.add(CopyKey(key=key, part=part, attempt_id=attempt.id))
    attempt.copy_indexed = True
    db.add(attempt)


def attempt_takes(db: Session, attempt: Attempt) -> list[Take]:
    ids = [int(t) for t in attempt.take_ids.split(",") if t.strip().isdigit()]
    if not ids:
        return []
    return list(db.exec(select(Take).where(Take.id.in_(ids))).all())


def index_unindexed(db: Session, limit: int = BACKFILL_BATCH) -> int:
    """Index up to ``limit`` attempts submitted before the index existed (locked, so that
    two workers starting together do not index one twice); how many were indexed."""
    attempts = db.exec(
        select(Attempt)
        .where(Attempt.copy_indexed.is_(False))
        .order_by(Attempt.id)
        .limit(limit)
        .with_for_update(skip_locked=True)
    ).all()
    for attempt in attempts:
        index_attempt(db, attempt, attempt_takes(db, attempt))
    return len(attempts)


def index_earlier_attempts() -> int:
    """Index every attempt submitted before the index existed, in batches (at start-up)."""
    total = 0
    while True:
        with write_session() as db:
            done = index_unindexed(db)
        total += done
        if done < BACKFILL_BATCH:
            return total
