"""A probe for ``queue_model.py``'s measuring run, loaded by the server only when
``GYROLAB_BENCH_PROBE`` names a 16-byte file: it counts, in that file, the places where a
request's thread gives up the interpreter -- SQLite calls (execute and fetch: each runs
``sqlite3_step`` with the GIL released) and trips to the thread pool (anyio's
``to_thread.run_sync``).  Not part of the app; never on its path otherwise."""

import os

_PATH = os.environ.get("GYROLAB_BENCH_PROBE")

if _PATH:
    import mmap
    import sqlite3
    import sqlite3.dbapi2
    import struct

    _file = open(_PATH, "r+b")  # noqa: SIM115 (held for the process's life)
    _counts = mmap.mmap(_file.fileno(), 16)

    def _add(slot: int) -> None:
        (value,) = struct.unpack_from("<q", _counts, slot * 8)
        struct.pack_into("<q", _counts, slot * 8, value + 1)

    class _CountingCursor(sqlite3.Cursor):
        def execute(self, *args, **kwargs):
            _add(0)
            return super().execute(*args, **kwargs)

        def executemany(self, *args, **kwargs):
            _add(0)
            return super().executemany(*args, **kwargs)

        def fetchone(self):
            _add(0)
            return super().fetchone()

        def fetchmany(self, *args, **kwargs):
            _add(0)
            return super().fetchmany(*args, **kwargs)

        def fetchall(self):
            _add(0)
            return super().fetchall()

    class _CountingConnection(sqlite3.Connection):
        def cursor(self, factory=_CountingCursor):
            return super().cursor(factory)

    _connect = sqlite3.connect

    def _counting_connect(*args, **kwargs):
        kwargs.setdefault("factory", _CountingConnection)
        return _connect(*args, **kwargs)

    sqlite3.connect = sqlite3.dbapi2.connect = _counting_connect  # SQLAlchemy uses dbapi2

    import anyio.to_thread

    _run_sync = anyio.to_thread.run_sync

    async def _counting_run_sync(*args, **kwargs):
        _add(1)
        return await _run_sync(*args, **kwargs)

    anyio.to_thread.run_sync = _counting_run_sync
