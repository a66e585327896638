"""Bounded expensive work: a pool of slots per kind of work in each process, and one slot
per person at a time.  Past that the request is refused at once -- 503 ("busy", Retry-After)
or 429 for a second job of the same person -- instead of queueing jobs that tie up the
worker's threads and memory (issue 31: one student's twelve renders of a 6,666-paragraph
discussion took 84–108 s and 1 GB).  Used for PDF reports (``GYROLAB_REPORT_RENDERS`` at
once, the class zip holding its teacher's slot while it renders) and for the Allan
analysis of an uploaded bench record (one at a time: 10⁷ readings take ≈ 13 s and
0.6 GB), and for a student's Excel workbook read as the text of its readings."""

from __future__ import annotations

import threading
from collections.abc import Iterable, Iterator
from contextlib import contextmanager

from app.core.exceptions import UserError
from app.db import give_way


class WorkPool:
    """``size`` jobs at once in this process, one per person; ``busy_key`` and
    ``person_key`` are the refusals' messages."""

    def __init__(self, size: int, busy_key: str, person_key: str, retry_s: int = 10) -> None:
        self._slots = threading.BoundedSemaphore(size)
        self._people: set[int] = set()
        # reentrant: a HeldStream's __del__ gives its slot back wherever the collector runs
        # it, which may be this very thread inside take() or give_back(), the lock held
        self._lock = threading.RLock()
        self.busy_key, self.person_key, self.retry_s = busy_key, person_key, retry_s

    @property
    def people(self) -> set[int]:
        return set(self._people)

    def take(self, person_id: int) -> None:
        """A slot for ``person_id``, or a UserError (429 / 503) at once.  The request
        then gives its work place back (``db.give_way``): the long job is
        bounded here and does not keep the worker's other requests waiting."""
        with self._lock:
            if person_id in self._people:
                raise UserError(self.person_key, status=429, headers={"Retry-After": "5"})
            if not self._slots.acquire(blocking=False):
                raise UserError(
                    self.busy_key, status=503, headers={"Retry-After": str(self.retry_s)}
                )
            self._people.add(person_id)
        give_way()

    def give_back(self, person_id: int) -> None:
        with self._lock:
            if person_id in self._people:
                self._people.discard(person_id)
                self._slots.release()

    @contextmanager
    def slot(self, person_id: int) -> Iterator[None]:
        self.take(person_id)
        try:
            yield
        finally:
            self.give_back(person_id)


class HeldStream:
    """A response body that holds a slot of ``work`` for ``person_id`` until it is read to
    its end, fails, is closed or is dropped (a download the client abandoned before its
    first block still gives its slot back)."""

    def __init__(self, work: WorkPool, person_id: int, blocks: Iterable) -> None:
        self._held = False
        work.take(person_id)  # refused now, with a page, not mid-download
        self._work, self._person, self._blocks = work, person_id, iter(blocks)
        self._held = True

    def __iter__(self) -> HeldStream:
        return self

    def __next__(self):
        try:
            return next(self._blocks)
        except BaseException:
            self.release()
            raise

    def release(self) -> None:
        if self._held:
            self._held = False
            self._work.give_back(self._person)

    def close(self) -> None:
        self.release()
        closing = getattr(self._blocks, "close", None)
        if closing is not None:
            closing()

    def __del__(self) -> None:
        self.release()


def held_while_streaming(name: str, person_id: int, blocks: Iterable) -> HeldStream:
    """``blocks`` as a response body holding a slot of pool ``name`` while it streams."""
    return HeldStream(pool(name), person_id, blocks)


WORKBOOKS_AT_ONCE = 2  # Excel workbooks read into a lab page's text per process
EXPORTS_AT_ONCE = 4  # streamed exports (1e6-sample CSV/JSON, the class's data zip) per process
_pools: dict[str, WorkPool] = {}
_pools_lock = threading.Lock()


def pool(name: str) -> WorkPool:
    """The process's pool for ``name`` ("reports", "exports", "workbooks" or "analysis"),
    made on first use."""
    with _pools_lock:
        if name not in _pools:
            from app.config import get_settings

            if name == "reports":
                size = get_settings().report_renders
                _pools[name] = WorkPool(size, "report.busy", "report.busy_person")
            elif name == "exports":
                _pools[name] = WorkPool(EXPORTS_AT_ONCE, "export.busy", "export.busy_person", 5)
            elif name == "workbooks":  # a student's .xlsx read: up to ≈ 7 s of parsing
                _pools[name] = WorkPool(
                    WORKBOOKS_AT_ONCE, "work.busy_workbook", "work.busy_person", 5
                )
            else:
                _pools[name] = WorkPool(1, "work.busy_analysis", "work.busy_person", 60)
        return _pools[name]
