"""Locking is declared on the route (web.deps.RowWriteSession / ReadOnlySession), and the
request's database session follows the declaration."""

from __future__ import annotations

import pytest
from fastapi import APIRouter, FastAPI
from fastapi.testclient import TestClient

from app.db import ROW_WRITER, WRITER_OPTION
from app.routes import api_routes, check_locking_declarations
from app.web.deps import Locking, ReadOnlySession, RowWriteSession, SessionDep, declared_locking


def writer_option(db) -> object:
    return db.get_bind().get_execution_options().get(WRITER_OPTION)


def test_the_database_session_follows_the_routes_declaration():
    router = APIRouter()

    @router.post("/exclusive")
    def exclusive(db: SessionDep):
        return {"writer": writer_option(db)}

    @router.post("/rows", dependencies=[RowWriteSession])
    def rows(db: SessionDep):
        return {"writer": writer_option(db)}

    @router.post("/read", dependencies=[ReadOnlySession])
    def read(db: SessionDep):
        return {"writer": writer_option(db)}

    @router.get("/page")
    def page(db: SessionDep):
        return {"writer": writer_option(db)}

    app = FastAPI()
    app.include_router(router)
    with TestClient(app) as client:
        assert client.post("/exclusive").json() == {"writer": True}
        assert client.post("/rows").json() == {"writer": ROW_WRITER}
        assert client.post("/read").json() == {"writer": None}
        assert client.get("/page").json() == {"writer": None}


def test_a_route_declares_one_locking_and_only_on_a_write():
    both = APIRouter()
    both.post("/x", dependencies=[RowWriteSession, ReadOnlySession])(lambda: None)
    with pytest.raises(RuntimeError, match="declares 2 lockings"):
        check_locking_declarations(both.routes)
    read = APIRouter()
    read.get("/y", dependencies=[RowWriteSession])(lambda: None)
    with pytest.raises(RuntimeError, match="changes nothing"):
        check_locking_declarations(read.routes)


def test_the_lab_sessions_writes_lock_rows_and_everything_else_is_exclusive():
    declared = {
        (route.path, method): declared_locking(route)
        for route in api_routes()
        for method in route.methods - {"GET", "HEAD"}
    }
    assert declared["/lab/sessions/{session_id}/csv/preview", "POST"] is Locking.none
    assert declared["/lab/sessions/{session_id}/csv", "POST"] is Locking.rows
    assert declared["/api/v1/sessions/{session_id}/submit", "POST"] is Locking.rows
    assert declared["/login", "POST"] is Locking.rows
    assert declared["/review/sessions/{session_id}/feedback", "POST"] is Locking.exclusive
    assert declared["/courses", "POST"] is Locking.exclusive
    # rows only where a lab session, an account's log-in or the token endpoint is written
    for (path, _), locking in declared.items():
        if locking is Locking.rows:
            assert path.startswith(("/lab/sessions", "/api/v1/sessions", "/log")) or (
                path == "/api/v1/auth/token"
            ), path


def test_row_writes_read_what_they_lock_in_the_handler_not_in_a_dependency():
    """Dependencies and the handler run on separate trips to the thread pool; a write lock
    taken by a dependency's query would be held across the gap (bench/README.md, issue 32).
    Only the caller's log-in is looked up in a dependency, and that without the lock
    (accounts.deps.load_login)."""
    from app.accounts.api_auth import api_caller
    from app.accounts.deps import csrf_protect, current_user, optional_user
    from app.web.deps import get_db

    login_lookups = {csrf_protect, current_user, optional_user, api_caller}

    def readers_of_the_session(dependant) -> set:
        found = set()
        for sub in dependant.dependencies:
            if any(inner.call is get_db for inner in sub.dependencies):
                found.add(sub.call)
            found |= readers_of_the_session(sub)
        return found

    checked = 0
    for route in api_routes():
        if declared_locking(route) is not Locking.rows or not route.methods - {"GET", "HEAD"}:
            continue
        checked += 1
        extra = readers_of_the_session(route.dependant) - login_lookups
        assert not extra, (route.path, sorted(getattr(c, "__name__", str(c)) for c in extra))
    assert checked >= 15


def test_a_save_and_a_submit_write_in_the_same_few_statements_however_many_positions(
    student_client,
):
    """Under load each statement inside the write lock is a wait for the interpreter
    (bench/README.md, issue 32): the takes of a file, their samples, the takes they
    supersede and the takes a submission freezes are each written in one statement."""
    import re

    from sqlalchemy import event
    from sqlalchemy.engine import Engine

    from tests.factories import DATA, new_session, post_form, post_json, save_manual

    written: list[str] = []
    shape = re.compile(r"(INSERT INTO \w+|UPDATE \w+ SET \w+|DELETE FROM \w+)")

    def count(conn, cursor, statement, parameters, context, executemany) -> None:
        found = shape.match(statement.lstrip())
        if found:
            written.append(found.group(1))

    event.listen(Engine, "before_cursor_execute", count)
    try:
        session_id = new_session(student_client)
        page = f"/lab/sessions/{session_id}"
        text = (DATA / "handout_horizontal.csv").read_text()
        saved = {}
        for attempt in ("first", "again"):  # again: the four it saved are superseded
            written.clear()
            body = {"part": "heading", "unit": "deg/h", "text": text}
            assert post_json(student_client, f"{page}/csv", body, page).status_code == 200
            saved[attempt] = list(written)
        written.clear()
        one = save_manual(student_client, session_id, "latitude", {"1": [10.0] * 10})
        assert one.status_code == 200
        saved["one"] = list(written)
        columns = {str(p): [10.0 + p] * 10 for p in range(1, 5)}
        assert save_manual(student_client, session_id, "latitude", columns).status_code == 200
        written.clear()
        submitted = post_form(student_client, f"{page}/submit", {}, page=page)
        frozen = list(written)
    finally:
        event.remove(Engine, "before_cursor_execute", count)
    # four positions, or four superseded as well, cost what one position does
    assert saved["first"] == saved["again"] == saved["one"], saved
    assert saved["one"].count("INSERT INTO take") == 1
    assert saved["one"].count("INSERT INTO sample_chunk") == 1
    # eight takes frozen in one statement
    assert submitted.status_code == 303, submitted.text
    assert frozen.count("UPDATE take SET frozen") == 1, frozen


def _gives_way(rows: bool, while_waiting=None, told=None, wrote=None) -> list[float]:
    """When (s after the write began) a write gave its request's place back; with
    ``while_waiting`` holding a lock from elsewhere until it returns, ``told`` (an event)
    set when the write gives way, and the clock when the write was done put in ``wrote``."""
    import threading
    import time

    from sqlmodel import select

    from app.db import give_way_hook, read_session, write_session
    from app.models import User

    began = time.perf_counter()
    calls: list[float] = []

    def gave_way() -> None:
        calls.append(time.perf_counter() - began)
        if told is not None:
            told.set()

    token = give_way_hook.set(gave_way)
    try:
        with read_session() as db:
            db.exec(select(User.id)).first()
        assert calls == [], "a read gave way"
        holder = threading.Thread(target=while_waiting) if while_waiting else None
        if holder:
            holder.start()
        began = time.perf_counter()
        with write_session(rows=rows) as db:
            db.exec(select(User.id)).first()
        if wrote is not None:
            wrote.append(time.perf_counter())
        if holder:
            holder.join()
    finally:
        give_way_hook.reset(token)
    return calls


def _let_go_when(told, let_go, missed: list[bool]) -> None:
    """Hold a lock until the write has given way (``told``), then ``let_go``; after 5 s
    let go anyway and note it in ``missed`` (the write waited without giving way).  So a
    test needs no deadline that a crowded machine's late thread could miss."""
    missed.append(not told.wait(5))
    let_go()


@pytest.mark.sqlite_only
@pytest.mark.parametrize("rows", [False, True])
def test_an_sqlite_write_keeps_its_place_unless_it_must_wait_for_another(app, rows):
    """A request waiting for a lock must not keep the worker's other requests out
    (web.admission), but one that gets it at once keeps its place: a write gives way when
    another process holds SQLite's write lock, or its process's turn is slow to come."""
    import sqlite3
    import threading

    from app.config import get_settings
    from app.db import get_engine, writer_turn

    assert _gives_way(rows) == []  # nobody else writing
    path = get_settings().database_url.removeprefix("sqlite:///")
    other = sqlite3.connect(path, isolation_level=None, check_same_thread=False)
    other.execute("BEGIN IMMEDIATE")  # another process's write, until this one gives way
    told, missed = threading.Event(), []
    release = threading.Thread(
        target=_let_go_when, args=(told, lambda: other.execute("COMMIT"), missed)
    )
    release.start()
    waited = _gives_way(rows, told=told)
    release.join()
    other.close()
    assert len(waited) == 1 and missed == [False], (waited, missed)  # gave way, then waited
    turn, taken = writer_turn(get_engine()), threading.Event()
    told, missed = threading.Event(), []

    def another_writer() -> None:  # this process's turn, held by another thread
        assert turn.acquire(1.0)
        taken.set()
        _let_go_when(told, turn.release, missed)

    writer = threading.Thread(target=another_writer, daemon=True)
    writer.start()
    assert taken.wait(10)
    waited = _gives_way(rows, told=told)
    writer.join(10)
    assert len(waited) == 1 and missed == [False], (waited, missed)
    assert waited[0] >= 0.04, waited  # after its patience, not at once


@pytest.mark.postgres_only
@pytest.mark.parametrize("rows", [False, True])
def test_a_postgresql_write_keeps_its_place_unless_another_holds_its_lock(app, rows):
    """PostgreSQL's writers take an advisory lock (shared for a row writer, exclusive for
    the rest) that a teacher's write may hold: a writer that gets it at once keeps its
    place; one that must wait gives its place back first, then waits."""
    import threading
    import time

    from app.db import WRITE_LOCK_KEY, get_engine

    assert _gives_way(rows) == []
    held, release, told, missed = threading.Event(), threading.Event(), threading.Event(), []
    let_go: list[float] = []
    wrote: list[float] = []

    def hold_exclusively() -> None:
        with get_engine().connect() as connection:
            connection.exec_driver_sql(f"SELECT pg_advisory_lock({WRITE_LOCK_KEY})")
            held.set()
            release.wait(10)
            connection.exec_driver_sql(f"SELECT pg_advisory_unlock({WRITE_LOCK_KEY})")
            connection.commit()

    holder = threading.Thread(target=hold_exclusively)
    holder.start()
    held.wait(5)

    def let_go_of_the_lock() -> None:
        let_go.append(time.perf_counter())
        release.set()

    calls = _gives_way(rows, lambda: _let_go_when(told, let_go_of_the_lock, missed), told, wrote)
    holder.join()
    # it gave way while the lock was held (let go only then), and then waited for it
    assert len(calls) == 1 and missed == [False], (calls, missed)
    assert wrote[0] > let_go[0]


@pytest.mark.sqlite_only
def test_a_write_leaves_the_connections_own_busy_timeout(app):
    """``BEGIN IMMEDIATE`` is tried without the busy wait first; the connection then has
    the busy timeout it was set up with again (a deployment or a test may shorten it), not
    the default."""
    from sqlalchemy import event, text

    from app.db import BUSY_TIMEOUT_MS, get_engine, write_session

    engine = get_engine()

    def shorten(dbapi_connection, _record) -> None:
        dbapi_connection.execute("PRAGMA busy_timeout = 321")

    event.listen(engine, "connect", shorten)
    engine.dispose()
    try:
        with write_session() as db:
            during = db.exec(text("PRAGMA busy_timeout")).scalar_one()
        with engine.connect() as connection:
            after = connection.exec_driver_sql("PRAGMA busy_timeout").scalar_one()
    finally:
        event.remove(engine, "connect", shorten)
        engine.dispose()
    assert BUSY_TIMEOUT_MS != 321
    assert during == after == 321


def test_a_write_to_ones_own_session_reads_it_as_locked_in_one_statement(student_client, backend):
    """On PostgreSQL a row writer locks its session's row and its owner's: the owner's own
    session is read already locked (``SELECT … FOR UPDATE``, as of the lock), not read,
    locked and read again (three round trips inside the write)."""
    from tests.factories import new_session, save_manual, statements_run

    session_id = new_session(student_client)
    with statements_run() as statements:
        saved = save_manual(student_client, session_id, "latitude", {"1": [10.0] * 10})
    assert saved.status_code == 200, saved.text
    locked = [s for s in statements if s.endswith("FOR UPDATE")]
    if backend == "sqlite":
        assert locked == [], statements
        return
    begun = next(i for i, s in enumerate(statements) if "pg_try_advisory_xact_lock" in s)
    inside = [s for s in statements[begun:] if "FROM lab_session" in s]
    assert len(inside) == 1 and inside[0].endswith("FOR UPDATE"), statements
    assert [s for s in locked if 'FROM "user"' in s] != [], statements


def test_a_streamed_position_marks_its_session_locked_in_one_statement(student_client, backend):
    """The stream's writes (a position started, saved, cleared) read their session as
    locked in one statement too; a session gone meanwhile is the stream's error message,
    not a crash."""
    import pytest

    from app.core.exceptions import UserError
    from app.lab import stream
    from app.web.render import SESSION_COOKIE
    from tests.factories import new_session, statements_run

    session_id = new_session(student_client)
    cookie = student_client.cookies.get(SESSION_COOKIE)
    with statements_run() as statements:  # the log-in checked in the same transaction
        marked = stream._mark_started(cookie, session_id, "heading", 1)
    assert (marked.stream_part, marked.stream_position) == ("heading", 1)
    reads = [s for s in statements if "FROM lab_session" in s]
    assert len(reads) == 1, statements
    assert reads[0].endswith("FOR UPDATE") == (backend == "postgresql"), statements
    with pytest.raises(UserError):
        stream._mark_started(cookie, session_id + 1000, "heading", 1)
