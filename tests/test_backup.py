"""``gyrolab backup`` / ``restore``: a consistent copy, checked before it replaces anything."""

from __future__ import annotations

import pytest
from sqlmodel import select

from app.cli.main import main
from app.db import engine_for, read_session
from app.models import Course, Role
from tests.factories import make_course, make_user


def course_names() -> list[str]:
    with read_session() as db:
        return sorted(db.exec(select(Course.name)).all())


@pytest.mark.sqlite_only
def test_backup_and_restore(app, tmp_path, capsys):
    teacher = make_user("t", Role.teacher)
    make_course(teacher, "Before the backup")
    target = tmp_path / "copy.db"
    assert main(["backup", str(target)]) == 0
    assert main(["backup", str(target)]) == 2  # never overwrites
    make_course(teacher, "After the backup")
    assert course_names() == ["After the backup", "Before the backup"]
    assert main(["restore", str(target)]) == 2  # needs --yes
    from app.config import get_settings

    engine_for(get_settings().database_url).dispose()
    assert main(["restore", str(target), "--yes"]) == 0
    assert course_names() == ["Before the backup"]


@pytest.mark.sqlite_only
def test_restore_refuses_bad_files(app, tmp_path, capsys):
    junk = tmp_path / "junk.db"
    junk.write_bytes(b"not a database at all" * 100)
    assert main(["restore", str(junk), "--yes"]) == 2
    assert "not an SQLite database" in capsys.readouterr().err
    import sqlite3

    other = tmp_path / "other.db"
    sqlite3.connect(other).execute("CREATE TABLE t (x)").connection.close()
    assert main(["restore", str(other), "--yes"]) == 2
    assert "not a GyroLab database" in capsys.readouterr().err
    assert main(["restore", str(tmp_path / "missing.db"), "--yes"]) == 2


def test_postgres_urls_get_pg_dump_instructions(monkeypatch, capsys):
    from app.cli.backup import postgres_hint

    text = postgres_hint("postgresql+psycopg://lab@db.example/gyrolab", "backup", "x.dump")
    assert text.startswith("PostgreSQL: pg_dump --format=custom --file=x.dump")
    assert "gyrolab" in postgres_hint("postgresql://u@h/gyrolab", "restore", "x.dump")


@pytest.mark.sqlite_only
def test_restore_refuses_while_a_server_uses_the_database(app, tmp_path, capsys):
    """Issue 31, item 5: every server process holds a shared lock beside the SQLite file for
    as long as it runs (app/serving_lock.py); restore wants it exclusively and says what to
    stop.  A real `gyrolab serve` holds it too (its lifespan takes it)."""
    from app.config import get_settings
    from app.serving_lock import hold_while_serving, release, servers_using

    url = get_settings().database_url
    target = tmp_path / "copy.db"
    assert main(["backup", str(target)]) == 0
    capsys.readouterr()
    server = hold_while_serving(url)
    try:
        assert servers_using(url)
        assert main(["restore", str(target), "--yes"]) == 2
        assert "a GyroLab server is using this database" in capsys.readouterr().err
    finally:
        release(server)
    assert not servers_using(url)
    engine_for(url).dispose()
    assert main(["restore", str(target), "--yes"]) == 0


@pytest.mark.sqlite_only
def test_a_running_apps_lifespan_holds_the_lock(app):
    from fastapi.testclient import TestClient

    from app.config import get_settings
    from app.serving_lock import servers_using

    url = get_settings().database_url
    with TestClient(app):
        assert servers_using(url)
    assert not servers_using(url)
