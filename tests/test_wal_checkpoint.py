"""SQLite's log checkpointed by a thread of the process, not by the request whose commit
made it long (app.wal_checkpoint)."""

from __future__ import annotations

import gc
import os
import sqlite3
import subprocess
import sys
import time

import pytest

from app.wal_checkpoint import (
    BACKSTOP_PAGES,
    CHECKPOINT_PAGES,
    CHECKPOINTS,
    Checkpoint,
    Checkpointer,
    checkpoint,
    log_pages,
)

BLOB = 8_000_000  # a 1e6-sample upload's bytes


def wal_database(path, autocheckpoint: int | None) -> sqlite3.Connection:
    """A WAL database; ``autocheckpoint`` and an emptied log as GyroLab's connections
    have them (None: SQLite's defaults)."""
    connection = sqlite3.connect(path, isolation_level=None)
    connection.execute("PRAGMA journal_mode=WAL")
    if autocheckpoint is not None:
        connection.execute(f"PRAGMA wal_autocheckpoint={autocheckpoint}")
        connection.execute("PRAGMA journal_size_limit=0")
    connection.execute("CREATE TABLE t (b BLOB)")
    return connection


def write_blob(connection: sqlite3.Connection, size: int = BLOB) -> None:
    connection.execute("BEGIN IMMEDIATE")
    connection.execute("INSERT INTO t VALUES (?)", (os.urandom(size),))
    connection.execute("COMMIT")


def test_a_commit_leaves_the_copy_into_the_database_file_to_the_checkpoint(tmp_path):
    """SQLite's default has the committing connection copy the log into the file (the
    8 MB twice in the request); GyroLab's connections leave it to ``checkpoint``."""
    default = wal_database(tmp_path / "default.db", autocheckpoint=None)
    write_blob(default)
    assert os.path.getsize(tmp_path / "default.db") > BLOB  # copied at the commit
    default.close()

    ours = wal_database(tmp_path / "ours.db", autocheckpoint=BACKSTOP_PAGES)
    write_blob(ours)
    assert os.path.getsize(tmp_path / "ours.db") < BLOB // 10  # still only in the log
    report = checkpoint(tmp_path / "ours.db")
    assert report.busy == 0 and report.log_frames == report.checkpointed_frames > BLOB // 4096
    assert os.path.getsize(tmp_path / "ours.db") > BLOB
    cursor = ours.execute("SELECT length(b) FROM t")
    assert cursor.fetchone() == (BLOB,)
    ours.close()


def test_the_log_is_measured_from_where_sqlite_last_started_it(tmp_path):
    path = tmp_path / "measured.db"
    connection = wal_database(path, autocheckpoint=BACKSTOP_PAGES)
    write_blob(connection)
    assert log_pages(path)[0] > BLOB // 4096
    checkpoint(path)
    write_blob(connection, 40_000)  # the next writer starts the log again, emptied
    assert 10 <= log_pages(path)[0] < 20
    connection.close()


def test_the_thread_checkpoints_a_watched_database_once_a_thousand_pages_wait(tmp_path):
    """About as many checkpoints as SQLite's own threshold makes, each outside a request."""
    path = str(tmp_path / "watched.db")
    connection = wal_database(path, autocheckpoint=BACKSTOP_PAGES)
    write_blob(connection, 40_000)
    looking = Checkpointer(interval_s=3600)  # its thread waits an hour: looks when told
    looking.watch(path)
    looking.look()
    assert looking.last == {}  # too few pages to copy yet
    looking.unwatch(path)

    checkpointer = Checkpointer(interval_s=0.02)
    checkpointer.watch(path)
    write_blob(connection)
    assert log_pages(path)[0] > CHECKPOINT_PAGES
    # it may look while the write is still going (its pages are in the log before its
    # commit) and copy what was committed; it looks again once the log has changed
    deadline = time.monotonic() + 20
    while (report := checkpointer.last.get(path)) is None or report.checkpointed_frames < 1000:
        assert time.monotonic() < deadline, f"no checkpoint of the write: {report}"
        time.sleep(0.02)
    assert report.busy == 0 and report.checkpointed_frames == report.log_frames
    assert os.path.getsize(path) > BLOB
    checkpointer.unwatch(path)
    assert not checkpointer.watching(path)
    connection.close()


def test_looking_never_drops_the_write_lock_this_process_holds(tmp_path):
    """Closing a descriptor of the log or its index would drop every POSIX lock the process
    holds on it: another process could then write while this one holds SQLite's write
    lock (a first version read the index: the concurrency test caught it)."""
    path = str(tmp_path / "locked.db")
    connection = wal_database(path, autocheckpoint=BACKSTOP_PAGES)
    write_blob(connection)
    holder = sqlite3.connect(path, isolation_level=None, timeout=0)
    holder.execute("BEGIN IMMEDIATE")
    checkpointer = Checkpointer(interval_s=3600)
    checkpointer.watch(path)
    checkpointer.look()
    assert checkpointer.last[path].checkpointed_frames > 0  # it did look, and copy
    other_process = (
        "import sqlite3, sys\n"
        "c = sqlite3.connect(sys.argv[1], isolation_level=None, timeout=0)\n"
        "try:\n"
        "    c.execute('BEGIN IMMEDIATE')\n"
        "    print('took the lock')\n"
        "except sqlite3.OperationalError as error:\n"
        "    print(error)\n"
    )
    answer = subprocess.run(
        [sys.executable, "-c", other_process, path], capture_output=True, text=True, check=True
    )
    assert answer.stdout.strip() == "database is locked"
    holder.execute("ROLLBACK")
    holder.close()
    connection.close()


def test_a_database_that_is_gone_is_left_alone(tmp_path):
    gone = tmp_path / "gone.db"
    assert checkpoint(gone) is None and log_pages(gone) is None
    assert not gone.exists()  # not created by looking
    checkpointer = Checkpointer(interval_s=3600)
    checkpointer.watch(str(gone))
    (tmp_path / "gone.db-wal").write_bytes(b"\0" * (2 * CHECKPOINT_PAGES * 4120))  # left behind
    checkpointer.look()
    assert checkpointer.last == {} and not gone.exists()


@pytest.mark.sqlite_only
def test_the_apps_connections_leave_checkpoints_to_the_thread_while_the_engine_lives(
    test_database, tmp_path
):
    from sqlalchemy import text

    from app.db import get_engine, make_engine

    with get_engine().connect() as connection:
        assert connection.execute(text("PRAGMA wal_autocheckpoint")).scalar() == BACKSTOP_PAGES
        assert connection.execute(text("PRAGMA journal_size_limit")).scalar() == 0
    assert CHECKPOINTS.watching(os.path.abspath(test_database.path))

    path = tmp_path / "own.db"
    engine = make_engine(f"sqlite:///{path}")
    with engine.connect() as connection:
        connection.execute(text("SELECT 1"))
    assert CHECKPOINTS.watching(str(path))
    engine.dispose()
    del engine, connection
    gc.collect()
    assert not CHECKPOINTS.watching(str(path))


def test_a_commit_in_the_same_clock_tick_as_the_last_look_is_still_checkpointed(monkeypatch):
    """Two looks during an 8 MB write copy only what was committed before it (the second
    sees nothing new and is done with that state); the write's commit then lands within
    the same tick of the file clock -- the log's time unchanged, only its size grown -- and
    must still be checkpointed (a full run with four test workers once waited forever)."""
    tick = 1_700_000_000_000_000_000  # the log's modification time, one coarse tick
    logs = [(1500, tick), (1900, tick), (1960, tick), (1960, tick)]
    seen = fake_log(monkeypatch, logs, [13, 13, 1960, 1960])
    looking = Checkpointer(interval_s=3600)
    looking._watched["db"] = 1  # watched, without starting the thread
    for _ in range(4):
        looking.look()
    assert seen == [13, 13, 1960]  # the commit copied once; the fourth look has nothing new
    assert looking.last["db"] == Checkpoint(0, 1960, 1960)


def fake_log(monkeypatch, logs: list[tuple[int, int]], committed: list[int]) -> list[int]:
    """``log_pages`` and ``checkpoint`` played from lists; returns the frames each
    checkpoint reported, as they come."""
    import app.wal_checkpoint as wal

    states, frames_left, seen = iter(logs), iter(committed), []
    monkeypatch.setattr(wal, "log_pages", lambda path: next(states))

    def fake_checkpoint(path):
        frames = next(frames_left)
        seen.append(frames)
        return Checkpoint(0, frames, frames)

    monkeypatch.setattr(wal, "checkpoint", fake_checkpoint)
    return seen


def test_a_commit_whose_index_lags_its_frames_is_still_checkpointed(monkeypatch):
    """The write's last frame is in the file (the log's size and time final) but SQLite's
    index not yet updated: checkpoints see the old 13 frames for a while.  The log is looked
    at again until they come (a full run on a loaded machine once left them for the next
    write: the second identical report had been taken for a stale log)."""
    tick = 1_700_000_000_000_000_000
    seen = fake_log(monkeypatch, [(1500, tick)] + [(1960, tick)] * 4, [13, 13, 13, 1960])
    looking = Checkpointer(interval_s=3600, clock=lambda: 0.0)
    looking._watched["db"] = 1  # watched, without starting the thread
    for _ in range(5):
        looking.look()
    assert seen == [13, 13, 13, 1960]  # copied once it was committed; then nothing new
    assert looking.last["db"] == Checkpoint(0, 1960, 1960)


def test_a_log_that_stays_longer_than_its_commits_is_left_alone_after_a_while(monkeypatch):
    """A log some other program restarted without emptying it: more pages in the file than
    committed, for good.  It is tried again until it has stayed so for STALE_AFTER_S."""
    from app.wal_checkpoint import STALE_AFTER_S

    tick = 1_700_000_000_000_000_000
    seen = fake_log(monkeypatch, [(1500, tick)] * 6, [13] * 6)
    times = iter([0.0, STALE_AFTER_S / 2, STALE_AFTER_S + 0.1, STALE_AFTER_S + 1, 99.0, 999.0])
    looking = Checkpointer(interval_s=3600, clock=lambda: next(times))
    looking._watched["db"] = 1
    for _ in range(6):
        looking.look()
    assert seen == [13, 13, 13]  # at 0, at half the wait, and past it: then left alone


def reader_and_long_log(path: str) -> tuple[sqlite3.Connection, sqlite3.Connection]:
    """A writer that has put a long log after a reader's snapshot began (the reader's
    snapshot holds the log's first few frames only)."""
    connection = wal_database(path, autocheckpoint=BACKSTOP_PAGES)
    write_blob(connection, 40_000)
    reader = sqlite3.connect(path, isolation_level=None)
    reader.execute("BEGIN")
    reader.execute("SELECT count(*) FROM t").fetchone()  # its snapshot: the small write
    write_blob(connection)
    return connection, reader


def test_a_checkpoint_a_reader_cut_short_is_finished_once_the_reader_is_gone(tmp_path):
    """A reader with an older snapshot lets a PASSIVE checkpoint copy only the frames it may
    still read past (in a class: the writer's own read lock, in the instant after its
    commit).  The log is looked at again until the copy is whole, not left for the next
    write (a full run on a loaded machine once looked in that instant: 13 of 1,970)."""
    path = str(tmp_path / "read.db")
    connection, reader = reader_and_long_log(path)
    looking = Checkpointer(interval_s=3600, clock=lambda: 0.0)
    looking._watched[path] = 1  # watched, without starting the thread
    looking.look()
    cut = looking.last[path]
    assert cut.busy == 0 and 0 <= cut.checkpointed_frames < cut.log_frames
    reader.execute("COMMIT")
    reader.close()
    looking.look()
    whole = looking.last[path]
    assert whole.checkpointed_frames == whole.log_frames > BLOB // 4096
    assert os.path.getsize(path) > BLOB
    connection.close()


def test_a_reader_that_stays_is_waited_for_a_while_then_left_alone(tmp_path):
    """A long reader (an export, a backup): the cut-short checkpoint is tried again until it
    has stayed the same for STALE_AFTER_S, then left until more is written."""
    from app.wal_checkpoint import STALE_AFTER_S

    path = str(tmp_path / "long.db")
    connection, reader = reader_and_long_log(path)
    times = iter([0.0, STALE_AFTER_S / 2, STALE_AFTER_S + 0.1, 99.0])
    looking = Checkpointer(interval_s=3600, clock=lambda: next(times))
    looking._watched[path] = 1
    tried = []
    for _ in range(4):
        looking.last.pop(path, None)
        looking.look()
        tried.append(path in looking.last)
    assert tried == [True, True, True, False]  # at 0, at half the wait, past it: then not
    reader.execute("COMMIT")
    reader.close()
    connection.close()


def test_an_engine_finalized_while_the_lock_is_held_never_blocks(tmp_path):
    """An engine's finalizer runs where the collector runs: in any thread, at any
    allocation -- once in the checkpointer's own thread inside ``look()``, the lock held.
    Its ``unwatch`` waited there for that lock for good, and every engine made after it
    waited in ``watch`` (a CI run hung so at an app's start)."""
    import threading

    from app.wal_checkpoint import Checkpointer

    checkpointer = Checkpointer(interval_s=3600.0)
    path = str(tmp_path / "gone.db")
    checkpointer.watch(path)
    checkpointer.watch(path)  # two engines on one file

    def finalizer_inside_a_locked_section() -> None:
        with checkpointer._lock:  # as look() holds it when the collector runs
            checkpointer.unwatch(path)

    thread = threading.Thread(target=finalizer_inside_a_locked_section, daemon=True)
    thread.start()
    thread.join(5.0)
    assert not thread.is_alive(), "unwatch waited for the lock its own thread held"
    assert checkpointer.watching(path)  # one engine is left: still watched
    checkpointer.unwatch(path)  # the last one, from another thread, the lock free
    assert not checkpointer.watching(path)
    checkpointer.watch(path)  # a new engine on the file: watched again
    assert checkpointer.watching(path)
