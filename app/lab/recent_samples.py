"""The samples of takes this process has just written, kept so that the results that
follow a save need not read them back (a 10⁶-sample upload is 8 MB to read and unpack).

A take's samples are keyed by its id, sample count and creation time: a take's samples
never change except by appending, which raises the count; a take id is only published
here once the transaction that wrote it has committed (a rolled-back id can be reused by
SQLite), and the creation time tells apart takes of another database that share an id.
Bounded in bytes; each worker process keeps its own, and a miss reads the database.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from datetime import UTC, datetime

import numpy as np
from sqlalchemy import event
from sqlmodel import Session

MAX_BYTES = 64 * 2**20
_PENDING = "gyrolab.recent_samples"

Key = tuple[int, int, str]
Arrays = tuple[np.ndarray, np.ndarray | None, np.ndarray | None]  # values, times, temperatures


class RecentSamples:
    """A thread-safe LRU of committed takes' sample arrays (read-only)."""

    def __init__(self, max_bytes: int = MAX_BYTES):
        self.max_bytes = max_bytes
        self._entries: OrderedDict[Key, Arrays] = OrderedDict()
        self._bytes = 0
        self._lock = threading.Lock()

    def get(self, take) -> Arrays | None:
        """The samples of ``take`` (a Take row) if this process wrote them."""
        key = key_of(take.id, take.n_samples, take.created_at)
        with self._lock:
            arrays = self._entries.get(key)
            if arrays is not None:
                self._entries.move_to_end(key)
            return arrays

    def put(self, key: Key, arrays: Arrays) -> None:
        size = _size(arrays)
        if size > self.max_bytes:
            return
        with self._lock:
            if key in self._entries:
                return
            self._entries[key] = arrays
            self._bytes += size
            while self._bytes > self.max_bytes:
                _, dropped = self._entries.popitem(last=False)
                self._bytes -= _size(dropped)

    def clear(self) -> None:
        with self._lock:
            self._entries.clear()
            self._bytes = 0


RECENT = RecentSamples()


def key_of(take_id: int, n_samples: int, created_at: datetime) -> Key:
    """The key of a take's samples; the time as UTC wall clock, whether the database
    returns it aware (PostgreSQL) or naive (SQLite)."""
    if created_at.tzinfo is not None:
        created_at = created_at.astimezone(UTC).replace(tzinfo=None)
    return take_id, int(n_samples), created_at.isoformat()


def _size(arrays: Arrays) -> int:
    return sum(a.nbytes for a in arrays if a is not None)


def _frozen(array: np.ndarray | None) -> np.ndarray | None:
    if array is None:
        return None
    view = np.asarray(array, dtype=float).view()
    view.flags.writeable = False
    return view


def hold(db: Session, take, values, times=None, temperatures=None) -> None:
    """Keep a just-flushed take's full samples (as stored, °/h) for when ``db`` commits."""
    key = key_of(take.id, take.n_samples, take.created_at)
    db.info.setdefault(_PENDING, []).append(
        (key, (_frozen(values), _frozen(times), _frozen(temperatures)))
    )


@event.listens_for(Session, "after_commit")
def _publish(db: Session) -> None:
    for key, arrays in db.info.pop(_PENDING, ()):
        RECENT.put(key, arrays)


@event.listens_for(Session, "after_rollback")
def _forget(db: Session) -> None:
    db.info.pop(_PENDING, None)
