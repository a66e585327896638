"""Models and Alembic migrations agree, and an empty database upgrades to head."""

from __future__ import annotations

import sqlite3

from alembic.autogenerate import compare_metadata
from alembic.migration import MigrationContext
from alembic.script import ScriptDirectory
from sqlmodel import SQLModel

import app.models  # noqa: F401
from app.db import make_engine
from app.migrate import alembic_config, upgrade_to_head


def test_upgrade_empty_database_and_no_pending_changes(tmp_path):
    url = f"sqlite:///{tmp_path / 'fresh.db'}"
    upgrade_to_head(url)
    engine = make_engine(url)
    with engine.connect() as connection:
        context = MigrationContext.configure(connection, opts={"compare_type": True})
        assert compare_metadata(context, SQLModel.metadata) == []
        head = ScriptDirectory.from_config(alembic_config(url)).get_current_head()
        assert context.get_current_revision() == head
    engine.dispose()
    upgrade_to_head(url)  # a second run is a no-op


def test_sqlite_pragmas(tmp_path):
    url = f"sqlite:///{tmp_path / 'p.db'}"
    engine = make_engine(url)
    with engine.connect() as connection:
        assert connection.exec_driver_sql("PRAGMA journal_mode").scalar() == "wal"
        assert connection.exec_driver_sql("PRAGMA foreign_keys").scalar() == 1
        assert connection.exec_driver_sql("PRAGMA busy_timeout").scalar() >= 5000
    engine.dispose()


def test_write_transactions_begin_immediate(tmp_path):
    """A write session holds the write lock from its first statement (BEGIN IMMEDIATE)."""
    from app.db import write_session

    url = f"sqlite:///{tmp_path / 'w.db'}"
    upgrade_to_head(url)
    engine = make_engine(url)
    with write_session(engine) as db:
        db.exec(SQLModel.metadata.tables["user"].select())  # a read only
        other = sqlite3.connect(tmp_path / "w.db", timeout=0.05, isolation_level=None)
        try:
            other.execute("BEGIN IMMEDIATE")
            raise AssertionError("second writer should have been locked out")
        except sqlite3.OperationalError as error:
            assert "locked" in str(error)
        finally:
            other.close()
    engine.dispose()


def test_populated_database_upgrades_across_revisions(tmp_path):
    """Rows written under an older schema survive and get the new columns' defaults."""
    from alembic import command

    url = f"sqlite:///{tmp_path / 'old.db'}"
    command.upgrade(alembic_config(url), "0002")
    connection = sqlite3.connect(tmp_path / "old.db")
    connection.executescript("""
        INSERT INTO user (username, display_name, role, password_hash, must_change_password,
                          created_at) VALUES ('t', 'T', 'teacher', 'x', 0, '2026-01-01');
        INSERT INTO course (name, teacher_id, archived, created_at)
            VALUES ('C', 1, 0, '2026-01-01');
        INSERT INTO assignment (course_id, title, instructions, latitude_deg, earth_rate_deg_h,
                                allowed_methods, simulator_preset, min_readings, created_at)
            VALUES (1, 'A', '', 40.0, 15.041, 'manual', 'teaching-fog', 10, '2026-01-01');
    """)
    connection.commit()
    connection.close()
    upgrade_to_head(url)
    connection = sqlite3.connect(tmp_path / "old.db")
    row = connection.execute(
        "SELECT azimuth_max_deg, tolerance_heading_deg, max_attempts, late_policy, reveal_truth "
        "FROM assignment"
    ).fetchone()
    (code,) = connection.execute("SELECT join_code FROM course").fetchone()
    connection.close()
    assert row == (360.0, 2.0, 3, "accept", "after_grading")
    assert len(code) == 8  # an existing course gets its join code


def test_a_file_database_has_a_connection_per_pool_thread(tmp_path):
    """40 connections (the thread pool's size), so requests never also queue for one;
    an in-memory database keeps SQLAlchemy's single-connection pool."""
    engine = make_engine(f"sqlite:///{tmp_path / 'pool.db'}")
    assert engine.pool.size() + engine.pool._max_overflow == 40
    engine.dispose()
    memory = make_engine("sqlite://")
    with memory.connect() as connection:
        assert connection.exec_driver_sql("SELECT 1").scalar() == 1
    memory.dispose()
