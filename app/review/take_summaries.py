"""What the class dashboard keeps of each take's readings: their quality checks, mean and
a digest of their bytes, made once per take.

A session's data summary (flags, fingerprints, evidence) is redone whenever any of its
takes changes, and in a class recording position after position that was every take of
the session again for each new one: read, unpacked, checked for spikes and gaps (≈ half
of a dashboard's CPU while a class records; bench/README.md, issue 32).  A take's used
readings never change but by appending or trimming, which change its count or trim; so
each take is read and checked once, and a session's summary is put together from its
takes' summaries.  Only parts whose readings the students recorded themselves (the data
evidence compares their readings) are read again."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

from app.lab.lru import LruCache
from app.lab.recent_samples import key_of
from app.lab.result_flags import PositionChecks, position_checks
from app.lab.results import PositionData


@dataclass(frozen=True, slots=True)
class TakeSummary:
    checks: PositionChecks
    mean: float
    digest: bytes  # SHA-256 of the used readings' bytes


TAKE_SUMMARIES = LruCache(65_536)  # ≈ 300 bytes each: a department's current takes


def summary_key(take) -> tuple:
    """A take's samples by id, count and creation time (as ``recent_samples`` keys
    them: a rolled-back id can come again), and the readings used by its trim."""
    return (*key_of(take.id, take.n_samples, take.created_at), take.trim_start or 0)


def take_summary(item: PositionData) -> TakeSummary:
    """The summary of a position's readings (with its samples), kept for its take when
    the samples read are the count its row was listed with (readings appended in between
    are summarised for this view only)."""
    summary = TakeSummary(
        position_checks(item), item.mean, hashlib.sha256(item.values.tobytes()).digest()
    )
    if item.n + item.trimmed == item.take.n_samples:
        TAKE_SUMMARIES.put(summary_key(item.take), summary)
    return summary


def known_summary(take) -> TakeSummary | None:
    return TAKE_SUMMARIES.get(summary_key(take))
