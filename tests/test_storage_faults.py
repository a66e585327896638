"""A database that cannot be written answers 503 with a clear message and recovers by
itself once it can (the file made read-only, then writable again)."""

from __future__ import annotations

import logging
import os
import stat

import pytest
from sqlmodel import select

from app.db import read_session
from app.models import LabSession
from tests.factories import (
    API,
    csrf_from,
    new_api_session,
    new_session,
    post_form,
    token_for,
    turn_heading_table,
)

pytestmark = pytest.mark.sqlite_only


@pytest.fixture
def read_only_database(var_dir):
    """Make the SQLite file and its folder read-only (yield), then writable again."""
    database = var_dir / "gyrolab.db"
    paths = [var_dir, database] + [var_dir / f"gyrolab.db-{s}" for s in ("wal", "shm")]
    modes = {p: p.stat().st_mode for p in paths if p.exists()}

    def make(read_only: bool) -> None:
        for path, mode in modes.items():
            os.chmod(path, stat.S_IMODE(mode) & ~0o222 if read_only else mode)

    yield make
    make(False)


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes to read-only files")
def test_read_only_database_answers_503_and_recovers(student_client, read_only_database, caplog):
    _check(student_client, read_only_database, caplog)


def test_read_only_database_answers_503_and_recovers_as_root(
    student_client, read_only_database, caplog, monkeypatch
):
    """As root (CI) file modes do not stop writes: SQLite's query_only pragma makes every
    connection refuse writes exactly as a read-only file does."""
    from sqlalchemy import event

    from app.db import get_engine

    engine = get_engine()
    state = {"read_only": False}

    def on_connect(dbapi_connection, _record) -> None:
        if state["read_only"]:
            dbapi_connection.execute("PRAGMA query_only = ON")

    event.listen(engine, "connect", on_connect)

    def make(read_only: bool) -> None:
        state["read_only"] = read_only
        engine.dispose()

    try:
        _check(student_client, make, caplog)
    finally:
        event.remove(engine, "connect", on_connect)


def _check(client, make_read_only, caplog) -> None:
    auth = token_for(client, "student1")
    session_id = new_api_session(client, auth)
    make_read_only(True)
    with caplog.at_level(logging.ERROR, logger="gyrolab"):
        for _ in range(3):
            reply = client.post(
                f"{API}/sessions", json={"station": {"latitude_deg": 40}}, headers=auth
            )
            assert reply.status_code == 503, reply.text
            assert "cannot be written" in reply.json()["detail"]
            assert reply.headers["Retry-After"] == "30"
        page = post_form(client, "/lab/sessions", {"station": "handout"}, page="/lab")
        assert page.status_code == 503 and "cannot be written" in page.text
        zh = client.post(
            f"{API}/sessions",
            json={"station": {"latitude_deg": 40}},
            headers={**auth, "Accept-Language": "zh-CN"},
        )
        assert zh.status_code == 503 and "数据库暂时无法写入" in zh.json()["detail"]
        assert client.get(f"/lab/sessions/{session_id}").status_code == 200  # reading goes on
    assert len([r for r in caplog.records if "cannot be written" in r.getMessage()]) <= 1
    make_read_only(False)
    again = client.post(f"{API}/sessions", json={"station": {"latitude_deg": 40}}, headers=auth)
    assert again.status_code == 201, again.text
    with read_session() as db:
        assert len(db.exec(select(LabSession)).all()) == 2


def test_a_write_lock_held_past_the_busy_timeout_answers_503_busy(student_client, var_dir):
    """Another writer holds SQLite's lock longer than the busy timeout (shortened to
    0.2 s here): pages and JSON answer 503 "busy, try again" with Retry-After, nothing is
    half-written, and the next request after the lock is released works."""
    import sqlite3

    from sqlalchemy import event

    from app.db import get_engine

    engine = get_engine()

    def short_timeout(dbapi_connection, _record) -> None:
        dbapi_connection.execute("PRAGMA busy_timeout = 200")

    event.listen(engine, "connect", short_timeout)
    engine.dispose()
    holder = sqlite3.connect(var_dir / "gyrolab.db", isolation_level=None)
    try:
        session_id = new_session_id(student_client)
        page = f"/lab/sessions/{session_id}"
        token = csrf_from(student_client, page)
        holder.execute("BEGIN IMMEDIATE")
        reply = turn_heading_table(student_client, session_id, 2, token)
        assert reply.status_code == 503 and reply.headers["Retry-After"] == "2"
        assert "very busy" in reply.json()["detail"]
        reply = student_client.post(f"{page}/submit", data={"csrf_token": token})
        assert reply.status_code == 503 and "very busy" in reply.text
        holder.execute("ROLLBACK")
        reply = turn_heading_table(student_client, session_id, 2, token)
        assert reply.status_code == 200
        with read_session() as db:
            assert db.get(LabSession, session_id).sim_table_heading == 2
    finally:
        holder.close()
        event.remove(engine, "connect", short_timeout)
        engine.dispose()


def new_session_id(client) -> int:

    return new_session(client)


def test_the_lms_grade_sender_reports_a_full_disk_as_requests_do(monkeypatch, caplog):
    """Issue 31, item 5: the background loop meets a full disk: the one storage message
    (once, then every ten minutes), no traceback, and the loop goes on."""
    import asyncio
    import logging
    import sqlite3
    import threading
    import time

    from sqlalchemy.exc import OperationalError

    from app.lti import grades
    from app.web import errors

    rounds = []

    def full_disk():
        rounds.append(1)
        raise OperationalError("SELECT 1", {}, sqlite3.OperationalError("database or disk is full"))

    monkeypatch.setattr(grades, "anything_queued", full_disk)
    monkeypatch.setattr(errors, "_storage_logged_at", [-1e9])

    async def three_rounds():
        task = asyncio.create_task(grades.run_sender(period_s=0.01))
        deadline = time.monotonic() + 20  # fails below, rather than waiting forever
        while len(rounds) < 3 and time.monotonic() < deadline:
            await asyncio.sleep(0.01)
        task.cancel()

    with caplog.at_level(logging.INFO):
        # a loop of its own, in a thread of its own: a browser test before this one on the
        # same worker may have left a running loop in the main thread
        runner = threading.Thread(target=lambda: asyncio.run(three_rounds()), daemon=True)
        runner.start()
        runner.join(30)
    assert len(rounds) >= 3 and not runner.is_alive(), rounds
    messages = [r for r in caplog.records if "cannot be written" in r.getMessage()]
    assert len(messages) == 1 and not any(r.exc_info for r in caplog.records)


def test_a_command_that_meets_the_write_lock_held_says_so_in_a_sentence(
    var_dir, monkeypatch, capsys
):
    """``gyrolab`` meets another writer holding the lock past the busy timeout (shortened to
    0.2 s here; PostgreSQL's lock_timeout likewise): one sentence and exit status 3,
    nothing written -- not a database traceback."""
    import sqlite3

    from app import db as app_db
    from app.cli.main import main
    from app.models import User

    monkeypatch.setattr(app_db, "BUSY_TIMEOUT_MS", 200)
    app_db.engine_for.cache_clear()
    holder = sqlite3.connect(var_dir / "gyrolab.db", isolation_level=None)
    holder.execute("BEGIN IMMEDIATE")
    try:
        status = main(["create-user", "--username", "held", "--password", "a-long-password-1"])
    finally:
        holder.execute("ROLLBACK")
        holder.close()
    assert status == 3
    assert capsys.readouterr().err == (
        "error: The lab is very busy this moment, so nothing was saved."
        " Try again in a few seconds.\n"
    )
    with read_session() as db:
        assert db.exec(select(User).where(User.username == "held")).first() is None
    app_db.engine_for.cache_clear()
    assert main(["create-user", "--username", "held", "--password", "a-long-password-1"]) == 0
