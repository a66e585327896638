"""Bounded work for PDF reports: at most ``GYROLAB_REPORT_RENDERS`` renders at once in a
process, and one at a time per person; past that a clear 503 (or 429 for a second render
of the same person) with Retry-After, never a queue of renders that ties up the worker's
threads and memory (issue 31: one student's twelve renders of a 6,666-paragraph
discussion took 84–108 s and 1 GB).  The class zip holds its teacher's one slot for as
long as it renders."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager
from functools import lru_cache

from app.config import get_settings
from app.core.exceptions import UserError

_people: set[int] = set()
_lock = threading.Lock()


@lru_cache(maxsize=1)
def _slots() -> threading.BoundedSemaphore:
    return threading.BoundedSemaphore(get_settings().report_renders)


def take_slot(person_id: int) -> None:
    """Take a render slot for ``person_id`` or refuse at once (UserError 429 / 503)."""
    with _lock:
        if person_id in _people:
            raise UserError("report.busy_person", status=429, headers={"Retry-After": "5"})
        if not _slots().acquire(blocking=False):
            raise UserError("report.busy", status=503, headers={"Retry-After": "10"})
        _people.add(person_id)


def give_back(person_id: int) -> None:
    with _lock:
        if person_id in _people:
            _people.discard(person_id)
            _slots().release()


@contextmanager
def render_slot(person_id: int) -> Iterator[None]:
    """One render for ``person_id`` (see :func:`take_slot`)."""
    take_slot(person_id)
    try:
        yield
    finally:
        give_back(person_id)
