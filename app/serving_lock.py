"""Who is using the SQLite database: every server process holds a shared lock on a file
beside it for as long as it runs, and ``gyrolab restore`` -- which replaces the database
under the server's feet -- takes the lock exclusively first, refusing while any server
holds it (issue 31).  ``fcntl.flock`` locks end with the process, so a killed server never
leaves a stale lock behind.  PostgreSQL restores go through ``pg_restore`` (the command
says so); this lock is for the SQLite file."""

from __future__ import annotations

import fcntl
import os
from contextlib import suppress
from pathlib import Path
from typing import IO

from sqlalchemy.engine import make_url


def lock_file_for(database_url: str) -> Path | None:
    """The lock file beside an SQLite database file (None for other databases)."""
    url = make_url(database_url)
    if not url.drivername.startswith("sqlite") or not url.database or url.database == ":memory:":
        return None
    return Path(url.database).with_name(Path(url.database).name + ".serving")


def hold_while_serving(database_url: str) -> IO | None:
    """Take the shared lock for this server process; the open file is the lock (close it to
    let go).  None when the database is not an SQLite file or the lock cannot be made."""
    path = lock_file_for(database_url)
    if path is None:
        return None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        handle = open(path, "a+")  # noqa: SIM115 -- held open for the server's lifetime
        fcntl.flock(handle, fcntl.LOCK_SH)
        handle.write(f"{os.getpid()}\n")
        handle.flush()
    except OSError:
        return None
    return handle


def release(handle: IO | None) -> None:
    if handle is not None:
        with suppress(OSError):
            fcntl.flock(handle, fcntl.LOCK_UN)
            handle.close()


def servers_using(database_url: str) -> bool:
    """Whether a server holds the database: a non-blocking exclusive lock fails."""
    path = lock_file_for(database_url)
    if path is None or not path.exists():
        return False
    with open(path, "a+") as handle:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            return True
        fcntl.flock(handle, fcntl.LOCK_UN)
        handle.truncate(0)  # no server left: the pids written there are gone
    return False
