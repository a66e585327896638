"""What PostgreSQL needs beyond "the same tests pass on it": migrations from empty and from
old rows, servers that start together, writers serialised across connections, NUL text,
and the pg_dump / pg_restore commands that ``gyrolab backup`` prints."""

from __future__ import annotations

import os
import shlex
import subprocess
import sys
import threading

import pytest
from alembic import command
from alembic.autogenerate import compare_metadata
from alembic.migration import MigrationContext
from alembic.script import ScriptDirectory
from sqlalchemy import text
from sqlmodel import SQLModel, select

import app.models  # noqa: F401
from app.db import make_engine, read_session, write_session
from app.migrate import alembic_config, upgrade_to_head
from app.models import Course, LabSession, Role
from tests.factories import login, make_course, make_user, post_form


@pytest.fixture
def empty_database(postgres):
    name = f"gyrolab_empty_{id(object())}"
    url = postgres.server.create_database(name)
    yield url
    postgres.server.drop_database(name)


def head_revision(url: str) -> str:
    return ScriptDirectory.from_config(alembic_config(url)).get_current_head()


def test_the_backend_is_the_one_named(app, backend):
    with read_session() as db:
        assert db.get_bind().dialect.name == backend


def test_empty_postgres_database_upgrades_with_no_pending_changes(empty_database):
    upgrade_to_head(empty_database)
    engine = make_engine(empty_database)
    with engine.connect() as connection:
        context = MigrationContext.configure(connection, opts={"compare_type": True})
        assert compare_metadata(context, SQLModel.metadata) == []
        assert context.get_current_revision() == head_revision(empty_database)
    engine.dispose()
    upgrade_to_head(empty_database)  # a second run is a no-op


@pytest.mark.slow
def test_servers_starting_together_migrate_once(empty_database):
    """Several servers run ``gyrolab migrate`` at once: one migrates, the rest wait."""
    env = {**os.environ, "GYROLAB_DATABASE_URL": empty_database}
    processes = [
        subprocess.Popen(
            [sys.executable, "-m", "app.cli.main", "migrate"],
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )
        for _ in range(3)
    ]
    outputs = [process.communicate(timeout=120)[0] for process in processes]
    assert [process.returncode for process in processes] == [0] * 3, outputs
    engine = make_engine(empty_database)
    with engine.connect() as connection:
        assert MigrationContext.configure(connection).get_current_revision() == head_revision(
            empty_database
        )
    engine.dispose()


def test_rows_from_an_old_schema_survive_and_seeds_become_64_bit(empty_database):
    command.upgrade(alembic_config(empty_database), "0002")
    engine = make_engine(empty_database)
    with engine.begin() as connection:
        connection.execute(
            text(
                'INSERT INTO "user" (username, display_name, role, password_hash,'
                " must_change_password, created_at) VALUES ('s', 'S', 'student', 'x', false,"
                " now())"
            )
        )
        connection.execute(
            text(
                "INSERT INTO lab_session (owner_id, title, latitude_deg, earth_rate_deg_h,"
                " heading_rotation, heading_start_deg, latitude_start_deg, latitude_step_deg,"
                " min_readings, simulator_preset, sim_seed, sim_azimuth_deg, sim_turns,"
                " sim_table_heading, sim_table_latitude, status, created_at, updated_at)"
                " VALUES (1, 'old', 40, 15.041, 'ccw', 0, 0, 90, 10, 'teaching-fog', 12345,"
                " 30, 0, 1, 1, 'in_progress', now(), now())"
            )
        )
    engine.dispose()
    upgrade_to_head(empty_database)
    engine = make_engine(empty_database)
    with engine.begin() as connection:
        connection.execute(text("UPDATE lab_session SET sim_seed = :seed"), {"seed": 2**62 + 7})
        row = connection.execute(text("SELECT title, sim_seed, status FROM lab_session")).one()
    engine.dispose()
    assert tuple(row) == ("old", 2**62 + 7, "in_progress")


@pytest.mark.postgres_only
def test_writers_queue_and_readers_do_not(app):
    """A write transaction holds the write lock until it commits; reads go straight through
    (SQLite's BEGIN IMMEDIATE has its own test in test_migrations)."""
    teacher = make_user("t", Role.teacher)
    course_id = make_course(teacher, "Queue")
    order: list[str] = []
    first_holds_lock = threading.Event()
    reader_done = threading.Event()

    def first_writer() -> None:
        with write_session() as db:
            db.get(Course, course_id)  # the transaction has begun: the lock is held
            first_holds_lock.set()
            reader_done.wait(10)
            db.get(Course, course_id).name = "first"
            order.append("first commits")

    def second_writer() -> None:
        first_holds_lock.wait(10)
        with write_session() as db:
            course = db.get(Course, course_id)
            order.append(f"second sees {course.name!r}")
            course.name = "second"

    def reader() -> None:
        first_holds_lock.wait(10)
        with read_session() as db:
            order.append(f"reader sees {db.get(Course, course_id).name!r}")
        reader_done.set()

    threads = [threading.Thread(target=f) for f in (first_writer, second_writer, reader)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(30)
    assert order == ["reader sees 'Queue'", "first commits", "second sees 'first'"]


def test_text_with_nul_is_refused_and_nothing_is_saved(app, client, backend):
    make_user("t", Role.teacher)
    assert login(client, "t").status_code == 303
    response = post_form(client, "/courses", {"name": "Lab\x00 1"})
    assert response.status_code == 400
    assert "NUL" in response.text
    with read_session() as db:
        assert db.exec(select(Course)).all() == []
    token = client.post("/api/v1/auth/token", data={"username": "\x00", "password": "x"})
    assert token.status_code == 400
    assert token.json()["key"] == "error.nul_text" and "NUL" in token.json()["detail"]


@pytest.mark.postgres_only
def test_printed_pg_dump_and_pg_restore_commands_work(app, postgres, tmp_path, capsys):
    """``gyrolab backup`` on PostgreSQL prints pg_dump; running it and the printed
    pg_restore into a fresh database brings the data back (SQLite: test_backup)."""
    from app.cli.main import main
    from app.config import get_settings
    from tests.pgserver import find_bindir

    bindir = find_bindir()
    if bindir is None:
        pytest.skip("pg_dump is not installed beside this server")
    teacher = make_user("t", Role.teacher)
    make_course(teacher, "Backed up 备份")
    with write_session() as db:
        db.add(LabSession(owner_id=teacher.id, title="x", latitude_deg=40, sim_seed=2**62))
    dump = tmp_path / "gyrolab.dump"
    assert main(["backup", str(dump)]) == 2
    backup_command = capsys.readouterr().out.strip().removeprefix("PostgreSQL: ")
    subprocess.run([str(bindir / "pg_dump"), *shlex.split(backup_command)[1:]], check=True)
    assert dump.stat().st_size > 0

    name = f"gyrolab_restored_{id(dump)}"
    restored_url = postgres.server.create_database(name)
    try:
        with pytest.MonkeyPatch.context() as patch:
            patch.setenv("GYROLAB_DATABASE_URL", restored_url)
            get_settings.cache_clear()
            assert main(["restore", str(dump)]) == 2
            restore_command = capsys.readouterr().out.strip().removeprefix("PostgreSQL: ")
            subprocess.run(
                [str(bindir / "pg_restore"), *shlex.split(restore_command)[1:]], check=True
            )
            engine = make_engine(restored_url)
            with engine.connect() as connection:
                names = connection.execute(text("SELECT name FROM course")).scalars().all()
                seeds = connection.execute(text("SELECT sim_seed FROM lab_session")).scalars()
                assert (names, list(seeds)) == (["Backed up 备份"], [2**62])
            engine.dispose()
    finally:
        get_settings.cache_clear()
        postgres.server.drop_database(name)


def test_a_read_request_sees_one_snapshot(app, backend):
    """A page built from several queries never mixes two states of the database (the load
    test caught the dashboard reading a take saved between two of its queries)."""
    teacher = make_user("t", Role.teacher)
    make_course(teacher, "First")
    with read_session() as db:
        before = db.exec(select(Course.name)).all()
        make_course(teacher, "Second")  # committed by another connection meanwhile
        assert db.exec(select(Course.name)).all() == before == ["First"]
    with read_session() as db:
        assert sorted(db.exec(select(Course.name)).all()) == ["First", "Second"]


def test_row_writers_lock_one_lab_session_not_the_database(app, backend):
    """Writes to one lab session queue on its row; a write to another session goes
    through meanwhile; an exclusive writer (accounts, courses) waits for the row writers
    in flight (and, being queued, holds up row writers that come after it: PostgreSQL
    grants locks in order).  On SQLite every writer is serialised by BEGIN IMMEDIATE, so
    there only the queue is checked."""
    from app.lab.service import own_session

    students = [make_user(f"rw{i}") for i in (1, 2)]
    with write_session() as db:
        sessions = []
        for student in students:
            session = LabSession(owner_id=student.id, title="t", latitude_deg=39.9)
            db.add(session)
            db.flush()
            sessions.append(session.id)
    order: list[str] = []
    holding = threading.Event()
    release = threading.Event()

    def first() -> None:
        with write_session(rows=True) as db:
            own_session(db, students[0], sessions[0]).title = "first"
            holding.set()
            release.wait(10)
            order.append("first commits")

    def same_session() -> None:
        holding.wait(10)
        with write_session(rows=True) as db:
            session = own_session(db, students[0], sessions[0])
            order.append(f"same session sees {session.title!r}")

    def other_session() -> None:
        holding.wait(10)
        with write_session(rows=True) as db:
            own_session(db, students[1], sessions[1]).title = "other"
        order.append("other session commits")
        if backend == "postgresql":
            release.set()  # it did not wait for the first

    def exclusive() -> None:
        holding.wait(10)
        if backend == "postgresql":
            release.wait(10)  # after the other session's write
        with write_session() as db:
            order.append(f"exclusive sees {db.get(LabSession, sessions[0]).title!r}")

    threads = [threading.Thread(target=f) for f in (first, same_session, other_session)]
    threads.append(threading.Thread(target=exclusive))
    for thread in threads:
        thread.start()
    if backend != "postgresql":
        holding.wait(10)
        release.set()
    for thread in threads:
        thread.join(30)
    assert order.index("same session sees 'first'") > order.index("first commits")
    assert order.index("exclusive sees 'first'") > order.index("first commits")
    if backend == "postgresql":
        assert order.index("other session commits") < order.index("first commits")


def test_one_session_per_student_and_assignment_when_started_at_once(app, backend):
    """Starting a session is a read-check-write ("none yet for this assignment?") under a
    row lock on the student: six starts at once give one session."""
    from concurrent.futures import ThreadPoolExecutor

    from app.lab.sessions import SessionSettings, start_session
    from app.models import Assignment

    teacher = make_user("tq", Role.teacher)
    student = make_user("sq")
    course_id = make_course(teacher, "Rows", (student,))
    with write_session() as db:
        assignment = Assignment(course_id=course_id, title="a", latitude_deg=39.9)
        db.add(assignment)
        db.flush()
        assignment_id = assignment.id

    def start(_: int) -> int:
        with write_session(rows=True) as db:
            found = db.get(Assignment, assignment_id)
            session, _created = start_session(db, student, SessionSettings(title=""), found, "t")
            db.add(session)
            db.flush()
            return session.id

    with ThreadPoolExecutor(6) as pool:
        ids = set(pool.map(start, range(6)))
    with read_session() as db:
        stored = db.exec(select(LabSession).where(LabSession.assignment_id == assignment_id))
        assert len(stored.all()) == 1
    assert len(ids) == 1


@pytest.mark.postgres_only
def test_a_log_in_locks_its_account_not_the_database(app, monkeypatch):
    """The throttle's count-then-charge runs under an advisory lock on the account alone:
    while alpha's attempt is being counted and charged, a log-in to another account from
    the same address, without a device cookie (a class behind one address, each student's
    first log-in), goes through; a second log-in to alpha waits for the first."""
    import app.accounts.security as security
    from app.config import get_settings
    from app.db import NAMED_LOCKS, get_engine

    for name in ("alpha", "beta"):
        make_user(name)
    settings = get_settings()
    counting = security.login_wait
    holding, release = threading.Event(), threading.Event()
    finished: list[str] = []

    def held_for_alpha(db, account, *args):
        wait = counting(db, account, *args)  # inside the locked transaction
        if account == "alpha" and not holding.is_set():
            holding.set()
            release.wait(10)
        return wait

    monkeypatch.setattr(security, "login_wait", held_for_alpha)

    def log_in_as(name: str, done: str) -> None:
        with write_session(rows=True) as db:
            outcome = security.log_in(db, name, "correct-horse-42", "10.0.0.2", settings)
            assert outcome.user is not None
        finished.append(done)

    first = threading.Thread(target=log_in_as, args=("alpha", "first alpha"))
    first.start()
    assert holding.wait(10)
    second = threading.Thread(target=log_in_as, args=("alpha", "second alpha"))
    second.start()
    with get_engine().connect() as watcher:  # the second alpha waits for the account's lock
        for _ in range(500):
            waiting = watcher.execute(
                text(
                    "SELECT count(*) FROM pg_locks WHERE locktype = 'advisory' AND NOT granted"
                    " AND classid = :space AND objsubid = 2 AND database = "
                    "(SELECT oid FROM pg_database WHERE datname = current_database())"
                ),
                {"space": NAMED_LOCKS},
            ).scalar()
            if waiting:
                break
            threading.Event().wait(0.01)
    assert waiting == 1
    beta = threading.Thread(target=log_in_as, args=("beta", "beta"))
    beta.start()
    beta.join(10)  # same address, no device cookie: not held up by alpha's check
    assert finished == ["beta"]
    release.set()
    first.join(10)
    second.join(10)
    assert finished[0] == "beta"
    assert sorted(finished[1:]) == ["first alpha", "second alpha"]


@pytest.mark.postgres_only
def test_a_write_lock_held_past_the_lock_timeout_answers_503_busy(student_client):
    """As SQLite's busy timeout does (test_storage_faults): a PostgreSQL writer waits for the
    writers' advisory lock at most the lock timeout (the busy timeout's 10 s; shortened to
    0.2 s here), then the request answers 503 "busy" with Retry-After and nothing written,
    instead of waiting for as long as another holds the lock; the next request after the
    lock is let go works."""
    from sqlalchemy import event

    from app.db import BUSY_TIMEOUT_MS, WRITE_LOCK_KEY, get_engine
    from tests.factories import csrf_from, new_session, turn_heading_table

    engine = get_engine()
    with engine.connect() as connection:
        setting = connection.exec_driver_sql("SHOW lock_timeout").scalar()
    assert setting == f"{BUSY_TIMEOUT_MS // 1000}s"

    def short_timeout(dbapi_connection, _record) -> None:
        with dbapi_connection.cursor() as cursor:
            cursor.execute("SET lock_timeout = 200")
        dbapi_connection.commit()

    event.listen(engine, "connect", short_timeout)
    engine.dispose()
    holder = make_engine(engine.url.render_as_string(hide_password=False))
    try:
        session_id = new_session(student_client)
        page = f"/lab/sessions/{session_id}"
        token = csrf_from(student_client, page)
        with holder.connect() as other:  # another process's exclusive write, held
            other.exec_driver_sql(f"SELECT pg_advisory_lock({WRITE_LOCK_KEY})")
            reply = turn_heading_table(student_client, session_id, 2, token)
            assert reply.status_code == 503 and reply.headers["Retry-After"] == "2"
            assert "very busy" in reply.json()["detail"]
            other.exec_driver_sql(f"SELECT pg_advisory_unlock({WRITE_LOCK_KEY})")
        reply = turn_heading_table(student_client, session_id, 2, token)
        assert reply.status_code == 200
        with read_session() as db:
            assert db.get(LabSession, session_id).sim_table_heading == 2
    finally:
        holder.dispose()
        event.remove(engine, "connect", short_timeout)
        engine.dispose()
