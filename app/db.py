"""Database engine and sessions, for SQLite (one server) and PostgreSQL (a department).

Write transactions are serialised on both, so that every read-check-write in the app (the
next sample offset, attempt numbers, throttle windows) is correct without per-site locking:

* SQLite: WAL journal, a busy timeout, foreign keys ON, and ``BEGIN IMMEDIATE`` for write
  transactions (a deferred ``BEGIN`` that reads and later writes fails with "database is
  locked" under concurrency). Read-only requests keep a deferred ``BEGIN`` so readers never
  queue behind writers.  A process's writers take turns in the order they asked
  (``app.writer_turn``) before ``BEGIN IMMEDIATE``, instead of sleeping in SQLite's busy
  handler.
* PostgreSQL: reads run in REPEATABLE READ (one snapshot per request, like SQLite);
  readers take no lock.  Writers come in two kinds, both under READ COMMITTED (each
  statement after a lock sees every earlier writer's commit):

  - a *row writer* (``row_writer``: the lab's work on one session -- recording, streaming,
    trimming, submitting -- starting a session, logging in and out) takes the app-wide
    advisory lock in SHARED mode, so row writers run in parallel, and locks what its
    read-check-write needs: rows with ``SELECT … FOR UPDATE`` (``lock_rows``: the lab
    session, then its owner for the storage quota; the student starting a session), names
    with advisory locks (``lock_keys``: a log-in's account, for the throttle),
    so two writes to one thing queue and writes to different things do not;
  - any other writer (``writer``: account administration, courses, assignments, reviews,
    joining a lab group -- rare, and their checks span many rows) takes the same advisory
    lock EXCLUSIVELY, as every writer did before: it waits for the row writers in flight
    and they wait for it.

  Single-row counters (rate windows, the idle timer) are atomic ``UPDATE … RETURNING``
  statements outside any serialised transaction (``statement_session``).
"""

from __future__ import annotations

import os
import sqlite3
from collections.abc import Callable, Iterator
from contextlib import contextmanager, suppress
from contextvars import ContextVar
from functools import lru_cache
from weakref import WeakKeyDictionary, finalize

from sqlalchemy import Engine, event, text
from sqlalchemy.engine import make_url
from sqlalchemy.exc import DBAPIError
from sqlmodel import Session, create_engine, select

from app.wal_checkpoint import BACKSTOP_PAGES, CHECKPOINTS
from app.writer_turn import WriterTurn

BUSY_TIMEOUT_MS = 10_000
WRITE_LOCK_KEY = 0x6779726F  # "gyro": the advisory lock every PostgreSQL writer takes
WRITER_OPTION = "gyrolab_writer"
ROW_WRITER = "rows"  # WRITER_OPTION's value for a row writer (True: an exclusive writer)
NAMED_LOCKS = 0x676C  # the two-key advisory lock space of ``lock_keys`` ("gl")


def is_sqlite(url: str) -> bool:
    return url.startswith("sqlite")


class UnstorableText(ValueError):
    """Text with a NUL character: PostgreSQL cannot store it, so neither backend takes it."""


STORAGE_FAULTS = (
    "readonly database",  # SQLite: the file or its folder is not writable
    "read-only",  # PostgreSQL: default_transaction_read_only, a hot standby
    "read only",
    "disk is full",  # SQLite: SQLITE_FULL
    "no space left",  # PostgreSQL: ENOSPC
    "disk full",
    "unable to open database file",  # SQLite: the folder lost its permissions
)


BUSY_FAULTS = (
    "database is locked",  # SQLite: the busy timeout ran out waiting for the write lock
    "database table is locked",
    "lock timeout",  # PostgreSQL: lock_timeout
    "could not obtain lock",
)


def database_busy(error: BaseException) -> bool:
    """Whether a database error means "the write lock stayed taken longer than the busy
    timeout" (a very busy moment, not a fault): the app answers 503 with Retry-After."""
    from sqlalchemy.exc import DBAPIError

    if not isinstance(error, DBAPIError):
        return False
    text = str(error.orig if error.orig is not None else error).lower()
    return any(fault in text for fault in BUSY_FAULTS)


def storage_unavailable(error: BaseException) -> bool:
    """Whether a database error means "cannot write now" (read-only or full storage)
    rather than a bug: the app answers 503 and recovers once the storage is writable."""
    from sqlalchemy.exc import DBAPIError

    if not isinstance(error, DBAPIError):
        return False
    text = str(error.orig if error.orig is not None else error).lower()
    return any(fault in text for fault in STORAGE_FAULTS)


def make_engine(url: str) -> Engine:
    engine = _sqlite_engine(url) if is_sqlite(url) else _postgres_engine(url)
    event.listen(engine, "before_cursor_execute", _refuse_nul_text)
    return engine


def _refuse_nul_text(_conn, _cursor, _statement, parameters, _context, _executemany) -> None:
    if _has_nul(parameters):
        raise UnstorableText("text may not contain NUL characters")


def _has_nul(value) -> bool:
    """Any text with NUL in statement parameters: one row (dict or tuple) or many."""
    if isinstance(value, str):
        return "\x00" in value
    if isinstance(value, dict):
        return any(_has_nul(item) for item in value.values())
    if isinstance(value, list | tuple):
        return any(_has_nul(item) for item in value)
    return False


# Set by the web layer for the request being served (web.admission): gives back the
# request's place among the worker's running requests.  Called, from any thread, when a
# write must wait for a lock someone else holds -- a request waiting for a lock must not
# keep the worker's other requests out -- and when a long job takes a pool of its own.
# (PostgreSQL's row locks, held for another write of the same rows' few milliseconds, are
# waited for with the place kept.)
give_way_hook: ContextVar[Callable[[], None] | None] = ContextVar("give_way_hook", default=None)


def give_way() -> None:
    """Give the running request's place back (nothing outside a request)."""
    hook = give_way_hook.get()
    if hook is not None:
        hook()


def _sqlite_engine(url: str) -> Engine:
    # A file database gets as many connections as the thread pool has threads (40), so
    # requests never queue for a connection as well as for the write lock.
    in_memory = make_url(url).database in (None, "", ":memory:")
    engine = create_engine(
        url,
        connect_args={"check_same_thread": False, "timeout": BUSY_TIMEOUT_MS / 1000},
        **({} if in_memory else {"pool_size": 10, "max_overflow": 30}),
    )

    @event.listens_for(engine, "connect")
    def _on_connect(dbapi_connection, _record) -> None:
        # Take transaction control away from pysqlite so that our BEGIN is the one used.
        dbapi_connection.isolation_level = None
        cursor = dbapi_connection.cursor()
        cursor.execute("PRAGMA journal_mode=WAL")
        cursor.execute(f"PRAGMA busy_timeout={BUSY_TIMEOUT_MS}")
        cursor.execute("PRAGMA foreign_keys=ON")
        cursor.execute("PRAGMA synchronous=NORMAL")
        if not in_memory:  # checkpoints by the process's thread (app.wal_checkpoint)
            cursor.execute(f"PRAGMA wal_autocheckpoint={BACKSTOP_PAGES}")
            cursor.execute("PRAGMA journal_size_limit=0")  # the log emptied when restarted
        cursor.close()

    @event.listens_for(engine, "begin")
    def _on_begin(connection) -> None:
        immediate = connection.get_execution_options().get(WRITER_OPTION, False)
        if not immediate:
            connection.exec_driver_sql("BEGIN")
            return
        fairy = connection.connection
        raw = fairy.dbapi_connection
        busy_ms = fairy.info.get("busy_timeout_ms")
        if busy_ms is None:  # as the connection was set up (a test may shorten it)
            (busy_ms,) = raw.execute("PRAGMA busy_timeout").fetchone()
            fairy.info["busy_timeout_ms"] = busy_ms
        if turns is None or not turns.acquire(raw):
            # a memory database, or the busy timeout waited: SQLite's lock without a turn
            _begin_immediate(raw, busy_ms)
            return
        try:
            _begin_immediate(raw, busy_ms)
        except BaseException:
            turns.hand_on(raw)
            raise

    turns = None if in_memory else _TurnsOnEngine(engine)
    if turns is not None:
        _TURNS[engine] = turns
        path = os.path.abspath(make_url(url).database)
        CHECKPOINTS.watch(path)
        finalize(engine, CHECKPOINTS.unwatch, path)
    return engine


_TURNS: WeakKeyDictionary[Engine, _TurnsOnEngine] = WeakKeyDictionary()
# how long a writer waits for its process's turn before it gives its request's place back
# (web.admission): a turn normally comes within a few writes of 2-20 ms
TURN_PATIENCE_S = 0.05


def _begin_immediate(raw, busy_ms: int) -> None:
    """``BEGIN IMMEDIATE``; if another process holds SQLite's write lock (a backup, the
    CLI, a second server), the request gives its place back first (``give_way``): that
    wait can last the busy timeout, ``busy_ms``, which the connection has again after."""
    try:
        raw.execute("PRAGMA busy_timeout=0")
        try:
            raw.execute("BEGIN IMMEDIATE")
        except sqlite3.OperationalError as error:
            if "locked" not in str(error) and "busy" not in str(error):
                raise
            give_way()
            raw.execute(f"PRAGMA busy_timeout={busy_ms}")
            raw.execute("BEGIN IMMEDIATE")
        else:
            raw.execute(f"PRAGMA busy_timeout={busy_ms}")
    except sqlite3.Error as error:  # as SQLAlchemy raises it: "locked" still answers 503
        with suppress(sqlite3.Error):
            raw.execute(f"PRAGMA busy_timeout={busy_ms}")
        raise DBAPIError.instance("BEGIN IMMEDIATE", None, error, sqlite3.Error) from error


def writer_turn(engine: Engine) -> WriterTurn | None:
    """The queue of a file SQLite engine's writers (None for other engines)."""
    turns = _TURNS.get(engine)
    return None if turns is None else turns.turn


class _TurnsOnEngine:
    """An engine's writers take turns (``WriterTurn``) from ``BEGIN IMMEDIATE`` until the
    connection's commit or rollback has finished (or the connection is closed)."""

    def __init__(self, engine: Engine) -> None:
        self.turn = WriterTurn()
        self.holders: set[int] = set()  # id() of the DBAPI connections that hold the turn
        dialect = engine.dialect
        commit, rollback = dialect.do_commit, dialect.do_rollback

        def do_commit(connection) -> None:
            try:
                commit(connection)
            finally:
                self.hand_on(connection)

        def do_rollback(connection) -> None:
            try:
                rollback(connection)
            finally:
                self.hand_on(connection)

        dialect.do_commit, dialect.do_rollback = do_commit, do_rollback
        event.listen(engine, "close", lambda raw, _record: self.hand_on(raw))
        event.listen(engine, "invalidate", lambda raw, _record, _error: self.hand_on(raw))

    def acquire(self, raw) -> bool:
        """Wait for the turn (at most the busy timeout): whether this connection holds it.
        A writer still waiting after ``TURN_PATIENCE_S`` gives its request's place back."""
        if not self.turn.acquire(BUSY_TIMEOUT_MS / 1000, TURN_PATIENCE_S, give_way):
            return False
        self.holders.add(id(raw))
        return True

    def hand_on(self, connection) -> None:
        """The turn to the next writer, if this connection (DBAPI or pooled) holds it."""
        key = id(getattr(connection, "dbapi_connection", connection))
        if key in self.holders:
            self.holders.discard(key)
            self.turn.release()


def _postgres_engine(url: str) -> Engine:
    # Each worker runs sync routes on a thread pool of 40; enough connections that a burst
    # waits on the write lock rather than on the pool.  A wait for a lock (the writers'
    # advisory lock, a row) lasts at most the busy timeout, as SQLite's does: past it the
    # request answers 503 "busy" (``database_busy``) instead of waiting for ever -- unless
    # the URL sets the connection's options itself.
    options = {} if "options" in make_url(url).query else {
        "options": f"-c lock_timeout={BUSY_TIMEOUT_MS}"}  # fmt: skip
    engine = create_engine(
        url, pool_pre_ping=True, pool_size=10, max_overflow=30, connect_args=options
    )

    @event.listens_for(engine, "begin")
    def _on_begin(connection) -> None:
        kind = connection.get_execution_options().get(WRITER_OPTION, False)
        if not kind:
            return
        shared = "_shared" if kind == ROW_WRITER else ""
        taken = connection.exec_driver_sql(
            f"SELECT pg_try_advisory_xact_lock{shared}({WRITE_LOCK_KEY})"
        ).scalar()
        if not taken:  # another holds it, maybe for a while: wait without a work place
            give_way()
            connection.exec_driver_sql(f"SELECT pg_advisory_xact_lock{shared}({WRITE_LOCK_KEY})")

    return engine


@lru_cache
def engine_for(url: str) -> Engine:
    return make_engine(url)


def get_engine() -> Engine:
    from app.config import get_settings

    return engine_for(get_settings().database_url)


def reader(engine: Engine) -> Engine:
    """The engine for read-only requests: on PostgreSQL, REPEATABLE READ, so that a page
    built from several queries sees one snapshot (as SQLite's WAL read transaction does);
    a transaction that only reads never fails to serialise."""
    if engine.dialect.name == "postgresql":
        return engine.execution_options(isolation_level="REPEATABLE READ")
    return engine


def writer(engine: Engine) -> Engine:
    """The same engine, but its transactions are serialised with every other writer."""
    return engine.execution_options(**{WRITER_OPTION: True})


def row_writer(engine: Engine) -> Engine:
    """The same engine for writes that lock the rows they check (``lock_rows``): on
    PostgreSQL they run in parallel with each other, on SQLite they are serialised."""
    return engine.execution_options(**{WRITER_OPTION: ROW_WRITER})


def is_row_writer(session: Session) -> bool:
    bind = session.get_bind()
    return bind.get_execution_options().get(WRITER_OPTION) == ROW_WRITER


def locks_rows(session: Session) -> bool:
    """Whether this session's writes lock the rows they read-check-write: a row writer's
    transaction on PostgreSQL (SQLite's single writer needs no locks)."""
    return is_row_writer(session) and session.get_bind().dialect.name == "postgresql"


def lock_rows(session: Session, model, *ids: int) -> bool:
    """``SELECT … FOR UPDATE`` of these rows in a row writer's transaction (held until it
    ends; SQLite's single writer needs none): whether rows were locked.  Callers lock in
    one order -- a lab session, then its owner -- so that two row writers never wait for
    each other in a cycle."""
    if not ids or not locks_rows(session):
        return False
    session.exec(select(model.id).where(model.id.in_(ids)).order_by(model.id).with_for_update())
    return True


def lock_keys(session: Session, *keys: str) -> bool:
    """Transaction-scoped advisory locks on names (a log-in's account) in a
    row writer's transaction on PostgreSQL, for a read-check-write over rows that do not
    exist yet (the throttle's counts, then a new row); taken in sorted order, in one
    statement (one round trip: a class logs in at once)."""
    if not keys or not locks_rows(session):
        return False
    names = sorted(set(keys))
    # a select list is evaluated left to right, so every caller takes them in one order
    calls = ", ".join(f"pg_advisory_xact_lock(:space, hashtext(:k{i}))" for i in range(len(names)))
    params = {"space": NAMED_LOCKS} | {f"k{i}": name for i, name in enumerate(names)}
    session.exec(text(f"SELECT {calls}"), params=params)
    return True


@contextmanager
def write_session(engine: Engine | None = None, *, rows: bool = False) -> Iterator[Session]:
    """A session for one write transaction: commits on success, rolls back on error
    (``rows``: a row writer, see ``row_writer``)."""
    bind = (row_writer if rows else writer)(engine or get_engine())
    with Session(bind, expire_on_commit=False) as session:
        try:
            yield session
            session.commit()
        except BaseException:
            session.rollback()
            raise


@contextmanager
def statement_session(engine: Engine | None = None) -> Iterator[Session]:
    """A session for single self-contained statements (an atomic UPDATE ... RETURNING) in
    the database's default isolation: READ COMMITTED on PostgreSQL, where concurrent
    updates of one row wait for each other instead of failing to serialise."""
    with Session(engine or get_engine(), expire_on_commit=False) as session:
        yield session


@contextmanager
def read_session(engine: Engine | None = None) -> Iterator[Session]:
    """A session for reading (one snapshot per transaction)."""
    with Session(reader(engine or get_engine()), expire_on_commit=False) as session:
        yield session
