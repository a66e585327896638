"""A first-come, first-served queue in front of SQLite's one write lock, within a process.

SQLite lets one connection write at a time; a writer that finds the lock taken sleeps in
SQLite's busy handler and tries again, after 1, 2, 5, 10 … and then every 100 ms.  Under a
class's burst of saves (the load test: 60 students' CSV saves and submits within seconds)
the waiters that have waited longest sleep longest, and a newcomer that asks just as the
lock is released takes it first: the lock itself was held 2–20 ms a write, but the wait
for it reached 0.85 s at p95 (an in-process trace of every write, bench/README.md).

Here the writers of one process take turns in the order they asked: the writer that
commits or rolls back hands its turn to the next at once, with no sleep.  SQLite's lock
is still what makes writes safe -- another process (a second worker, the CLI) meets it as
before -- and a writer that has waited for its turn as long as the busy timeout goes on to
SQLite's lock without one, as every writer did before this queue.
"""

from __future__ import annotations

import threading
from collections import deque
from collections.abc import Callable


class WriterTurn:
    """A lock granted in the order it was asked for (first come, first served)."""

    def __init__(self) -> None:
        self._mutex = threading.Lock()
        self._held = False
        self._holder: int | None = None  # the thread that holds the turn
        self._waiting: deque[threading.Lock] = deque()

    def acquire(
        self, timeout: float, patience: float = 0.0, impatient: Callable[[], None] | None = None
    ) -> bool:
        """Wait up to ``timeout`` seconds for the turn: whether it was granted.  A thread
        that already holds it is not granted a second one and does not wait (a write
        opened inside another meets SQLite's lock at once, as it would without the queue).
        ``impatient``: called once if the turn has not come within ``patience`` seconds
        (the writer keeps its place in the queue)."""
        me = threading.get_ident()
        with self._mutex:
            if not self._held:
                self._held, self._holder = True, me
                return True
            if self._holder == me:
                return False
            signal = threading.Lock()
            signal.acquire()
            self._waiting.append(signal)
        if impatient is not None and 0 < patience < timeout:
            granted = signal.acquire(timeout=patience)
            if not granted:
                impatient()
                granted = signal.acquire(timeout=timeout - patience)
        else:
            granted = signal.acquire(timeout=timeout)
        with self._mutex:
            if not granted and signal in self._waiting:
                self._waiting.remove(signal)
                return False
            self._holder = me  # granted, or handed over just as the wait ran out
        return True

    def release(self) -> None:
        """Hand the turn to the writer that has waited longest, or free it."""
        with self._mutex:
            self._holder = None
            if self._waiting:
                self._waiting.popleft().release()
            else:
                self._held = False

    @property
    def queued(self) -> int:
        """How many writers are waiting for the turn."""
        return len(self._waiting)
