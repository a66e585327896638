"""Per-minute request limits without a database write per request.

The limit lives in the database: each API token (and each browser log-in session) has a
one-minute window, ``window_start`` and ``window_count``.  A worker process does not count
every request there; it *leases* a few requests of the window at once with one atomic
``UPDATE … RETURNING`` and admits them from memory.  A lease is granted only out of what
the window has left, so the requests admitted by all workers and hosts together never
exceed the limit; near the limit leases shrink to one request, so the count stays exact
where it matters.  What a worker leased and did not use is lost when the window ends (at
most ``MAX_LEASE - 1`` requests per worker per window).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass
from datetime import datetime, timedelta

from sqlalchemy import bindparam, case, or_, update

from app.models import utcnow

WINDOW = timedelta(minutes=1)
MAX_LEASE = 16  # requests leased per database write at most
LEASE_SHARE = 8  # a lease takes at most 1/8 of what the window has left


@dataclass
class Lease:
    window_start: datetime
    left: int  # requests this process may still admit in that window
    count: int  # the window's count in the database after the last lease


@dataclass(frozen=True)
class Admission:
    admitted: bool
    retry_after: int = 0  # seconds until the window ends, when refused


class RateLeases:
    """The leases of one process, by the row's token digest (unique and never reused,
    unlike a row id after a database is restored); thread-safe."""

    def __init__(self) -> None:
        self._leases: dict[str, Lease] = {}
        self._lock = threading.Lock()

    def clear(self) -> None:
        with self._lock:
            self._leases.clear()

    def admit(
        self,
        key: str,
        limit: int,
        lease_from_database: Callable[[int, datetime], tuple[datetime, int] | None],
    ) -> Admission:
        """Admit one request for ``key`` from this process's lease, leasing more from the
        database when it is used up.  ``lease_from_database(size, now)`` adds ``size`` to
        the row's window (starting a new one when the last is over) and returns the
        window's start and count afterwards (None: the row is gone)."""
        now = utcnow()
        with self._lock:
            lease = self._leases.get(key)
            if lease is not None and now - lease.window_start < WINDOW and lease.left > 0:
                lease.left -= 1
                return Admission(True)
            known = lease.count if lease is not None and now - lease.window_start < WINDOW else 0
        size = max(1, min(MAX_LEASE, (limit - known) // LEASE_SHARE))
        counted = lease_from_database(size, now)
        if counted is None:
            return Admission(False, 1)
        window_start, count = counted
        granted = max(0, min(size, limit - (count - size)))
        with self._lock:
            current = self._leases.get(key)
            left = granted - 1 if granted else 0
            if current is not None and current.window_start == window_start:
                current.left += left
                current.count = max(current.count, count)
            else:
                self._leases[key] = Lease(window_start, left, count)
            if len(self._leases) > 100_000:  # long-gone tokens and sessions
                self._forget_old(now)
        if granted:
            return Admission(True)
        return Admission(False, max(60 - int((now - window_start).total_seconds()), 1))

    def _forget_old(self, now: datetime) -> None:
        for key in [k for k, v in self._leases.items() if now - v.window_start >= WINDOW]:
            del self._leases[key]


LEASES = RateLeases()


def lease_update(model):
    """``UPDATE model SET window += :size WHERE id = :row_id RETURNING window``, in bound
    parameters (``lease_parameters``): atomic on its own (a row lock on PostgreSQL), so it
    needs no serialised write transaction."""
    window_over = or_(model.window_start.is_(None), model.window_start <= bindparam("window_ended"))
    return (
        update(model)
        .where(model.id == bindparam("row_id"))
        .values(
            window_start=case((window_over, bindparam("now")), else_=model.window_start),
            window_count=case(
                (window_over, bindparam("size")), else_=model.window_count + bindparam("size")
            ),
        )
        .returning(model.window_start, model.window_count)
    )


def lease_parameters(row_id: int, size: int, now: datetime) -> dict:
    return {"row_id": row_id, "size": size, "now": now, "window_ended": now - WINDOW}
