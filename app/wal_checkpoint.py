"""SQLite's write-ahead log copied back into the database file by a thread of its own.

In WAL mode a commit appends the changed pages to ``gyrolab.db-wal``; a *checkpoint*
copies them into ``gyrolab.db``.  By default the connection whose commit takes the log
past 1,000 pages (4 MB) runs that checkpoint itself, inside its request: a 1e6-sample
upload (8 MB) paid ≈ 18 ms of its ≈ 50 ms copying its own pages a second time (issue 32,
bench/README.md).  Here a process's connections leave checkpoints to one daemon thread
that looks at each database's log a few times a second and checkpoints it once it holds
1,000 pages -- SQLite's own threshold, so there are about as many checkpoints as before,
each outside a request.  It learns that from the log file's size and time (``os.stat``):
the connections set ``journal_size_limit = 0``, so SQLite empties the log whenever it
starts it again after a complete checkpoint, and its size is what was written since.
The thread never opens the log or its index itself: closing any descriptor of a file
drops every POSIX lock the process holds on it -- SQLite's locks on the index included
(another process then took the write lock while this one held it: the concurrency test
caught that in a first version).  The checkpoint is SQLite's PASSIVE one, the kind the
connections ran: it waits for no reader or writer and copies what it can, so a request
never waits for it and the database is as safe as before (a commit is durable once in
the log, which SQLite replays after a crash).

A connection still checkpoints itself once the log reaches ``BACKSTOP_PAGES`` (a process
whose thread cannot keep up, or a long command-line import).
"""

from __future__ import annotations

import logging
import os
import queue
import sqlite3
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import quote

BACKSTOP_PAGES = 16_384  # 64 MB of 4 KiB pages: where a connection checkpoints itself
CHECKPOINT_PAGES = 1_000  # SQLite's default threshold, now the thread's
LOOK_EVERY_S = 0.25  # how often the thread looks at the logs
FRAME_BYTES = 4096 + 24  # a page in the log: the page (SQLite's default size) and its header
# A log whose file holds more pages than SQLite reports committed, and that neither grows nor
# has more committed for this long, is left alone until it changes (a log some other program
# restarted without emptying it).  Shorter waits mistook a commit whose frames were all in
# the file, its index not yet updated, for such a log, and left it for the next write (a
# full test run on a loaded machine).
STALE_AFTER_S = 2.0


@dataclass
class Checkpoint:
    """What SQLite reported: whether it had to stop short (``busy``), the frames in the
    log and the frames now in the database file (-1 when the database is not in WAL)."""

    busy: int
    log_frames: int
    checkpointed_frames: int


def log_pages(path: str | Path) -> tuple[int, int] | None:
    """The pages in ``path``'s log since SQLite last started it (its size over a frame's),
    and the log's modification time (ns); None when there is no log.  ``os.stat`` only:
    no descriptor of the log is opened (see the module)."""
    try:
        status = os.stat(f"{path}-wal")
    except OSError:
        return None
    return status.st_size // FRAME_BYTES, status.st_mtime_ns


def checkpoint(path: str | Path) -> Checkpoint | None:
    """One PASSIVE checkpoint of the database at ``path``; None where it cannot be opened
    or written (gone, read-only, a full disk: the next commit's log is simply longer)."""
    try:
        connection = sqlite3.connect(
            f"file:{quote(str(path))}?mode=rw", uri=True, timeout=0, isolation_level=None
        )
    except sqlite3.Error:
        return None
    try:
        return Checkpoint(*connection.execute("PRAGMA wal_checkpoint(PASSIVE)").fetchone())
    except sqlite3.Error:
        return None
    finally:
        connection.close()


class Checkpointer:
    """The thread that checkpoints the databases it watches once ``threshold`` pages wait."""

    def __init__(
        self,
        interval_s: float = LOOK_EVERY_S,
        threshold: int = CHECKPOINT_PAGES,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.interval_s = interval_s
        self.threshold = threshold
        self._clock = clock
        self._watched: dict[str, int] = {}  # path → engines using it
        # path → the log's (pages, mtime) when last done with: the size as well as the time,
        # as a file's time moves in the kernel's clock ticks (a few ms) and a commit's last
        # frame can land in the tick of the look before it
        self._checked: dict[str, tuple[int, int]] = {}
        # path → the log's state and the checkpoint's report when first seen together, and when
        self._unchanged: dict[str, tuple[tuple[int, int], Checkpoint, float]] = {}
        self._lock = threading.Lock()
        # paths an engine stopped using, to forget under the lock: unwatch runs in the
        # engine's finalizer, which the collector may run in any thread at any allocation --
        # this thread's own, inside look() with the lock held (a test run hung so, every
        # later engine waiting on the lock); a SimpleQueue's put may be called there
        self._gone: queue.SimpleQueue[str] = queue.SimpleQueue()
        self._thread: threading.Thread | None = None
        self.last: dict[str, Checkpoint] = {}  # path → the last checkpoint's report

    def watch(self, path: str) -> None:
        """Checkpoint ``path``'s log from now on (once per engine that uses it)."""
        with self._lock:
            self._forget_gone()
            self._watched[path] = self._watched.get(path, 0) + 1
            if self._thread is None or not self._thread.is_alive():
                self._thread = threading.Thread(
                    target=self._run, name="gyrolab-wal-checkpoint", daemon=True
                )
                self._thread.start()

    def unwatch(self, path: str) -> None:
        """One engine fewer uses ``path`` (the last one gone: no longer watched).  Never
        waits for the lock: where another holder has it (or this thread, the finalizer run
        inside a locked section), the path is forgotten by the next one to take it."""
        self._gone.put(path)
        if self._lock.acquire(blocking=False):
            try:
                self._forget_gone()
            finally:
                self._lock.release()

    def _forget_gone(self) -> None:
        """Forget, under the lock, the engines that stopped using their paths."""
        while True:
            try:
                path = self._gone.get_nowait()
            except queue.Empty:
                return
            left = self._watched.get(path, 0) - 1
            if left > 0:
                self._watched[path] = left
            else:
                self._watched.pop(path, None)
                self._checked.pop(path, None)
                self._unchanged.pop(path, None)
                self.last.pop(path, None)

    def watching(self, path: str) -> bool:
        with self._lock:
            self._forget_gone()
            return path in self._watched

    def look(self) -> None:
        """Checkpoint every watched database whose log holds ``threshold`` pages or more
        and has changed since its last checkpoint here; a log with pages beyond what SQLite
        reports committed, or whose checkpoint a reader cut short, is looked at again until
        it has stayed as it is for ``STALE_AFTER_S`` (then, as SQLite's own would, once more
        is written)."""
        with self._lock:
            self._forget_gone()
            paths = list(self._watched)
        for path in paths:
            log = log_pages(path)
            if log is None:
                continue
            pages = log[0]
            if pages < self.threshold or self._checked.get(path) == log:
                continue
            report = checkpoint(path)
            with self._lock:
                if path not in self._watched:
                    continue
                # done with this state of the log once the checkpoint copied all of it; a
                # write still going (its pages in the file, its commit or the index's
                # update not yet), or a reader whose snapshot stopped the copy short (the
                # writer's own, in the instant after its commit), is looked at again,
                # unless the log and the report stay as they are for STALE_AFTER_S (a log
                # some other program restarted without emptying it; a long reader)
                whole = report is not None and report.checkpointed_frames >= report.log_frames
                complete = whole and report.log_frames >= pages
                if report is None or complete or self._stale(path, log, report):
                    self._checked[path] = log
                    self._unchanged.pop(path, None)
                if report is not None:
                    self.last[path] = report

    def _stale(self, path: str, log: tuple[int, int], report: Checkpoint) -> bool:
        """Whether ``path``'s log and its checkpoint's report have stayed as they are now for
        ``STALE_AFTER_S`` (under the lock)."""
        now = self._clock()
        seen = self._unchanged.get(path)
        if seen is None or seen[:2] != (log, report):
            self._unchanged[path] = (log, report, now)
            return False
        return now - seen[2] >= STALE_AFTER_S

    def _run(self) -> None:
        stop = threading.Event()  # never set: a daemon thread ends with its process
        while not stop.wait(self.interval_s):
            try:
                self.look()
            except Exception:  # noqa: BLE001 -- the connections' backstop still checkpoints
                logging.getLogger(__name__).exception("WAL checkpoint failed")


CHECKPOINTS = Checkpointer()
