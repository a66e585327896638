"""``gyrolab backup`` and ``gyrolab restore`` for the SQLite database.

Backup uses SQLite's online backup API: a consistent copy even while the server writes.
Restore checks the file (integrity check, a GyroLab schema) before copying it over the
live database, then migrates it to the current schema.  PostgreSQL installations use
``pg_dump`` / ``pg_restore`` (printed by the command).
"""

from __future__ import annotations

import shlex
import sqlite3
from pathlib import Path

from sqlalchemy.engine import make_url

from app.core.exceptions import UserError


class BackupError(UserError):
    """Why a backup or a restore cannot be done (a ``cli.backup_*`` message key)."""


def sqlite_path(database_url: str) -> Path | None:
    url = make_url(database_url)
    if not url.drivername.startswith("sqlite"):
        return None
    if not url.database or url.database == ":memory:":
        raise BackupError("cli.backup_in_memory")
    return Path(url.database)


def postgres_hint(database_url: str, action: str, target: str) -> str:
    """The pg_dump / pg_restore command for this database (the password comes from
    ~/.pgpass or PGPASSWORD, never from the command line)."""
    url = make_url(database_url)
    server = f"--host={url.host or 'localhost'} --port={url.port or 5432}"
    if url.username:
        server += f" --username={shlex.quote(url.username)}"
    if action == "backup":
        return (
            f"PostgreSQL: pg_dump --format=custom --file={shlex.quote(target)} {server} "
            f"{shlex.quote(url.database or '')}"
        )
    return (
        f"PostgreSQL: pg_restore --clean --if-exists --no-owner "
        f"--dbname={shlex.quote(url.database or '')} {server} {shlex.quote(target)}"
    )


def check_file(path: Path) -> None:
    if not path.is_file():
        raise BackupError("cli.backup_missing", path=path)
    try:
        connection = sqlite3.connect(f"file:{path}?mode=ro", uri=True)
        try:
            result = connection.execute("PRAGMA integrity_check").fetchone()[0]
            tables = {
                row[0]
                for row in connection.execute("SELECT name FROM sqlite_master WHERE type='table'")
            }
        finally:
            connection.close()
    except sqlite3.DatabaseError as error:
        raise BackupError("cli.backup_not_sqlite", path=path, reason=error) from None
    if result != "ok":
        raise BackupError("cli.backup_integrity", path=path, result=result)
    if not {"alembic_version", "user"} <= tables:
        raise BackupError("cli.backup_not_gyrolab", path=path)


def backup(database: Path, target: Path) -> None:
    if not database.exists():
        raise BackupError("cli.backup_no_database", path=database)
    if target.exists():
        raise BackupError("cli.backup_exists", path=target)
    source = sqlite3.connect(database)
    destination = sqlite3.connect(target)
    try:
        with destination:
            source.backup(destination)
    finally:
        destination.close()
        source.close()
    check_file(target)


def restore(source_file: Path, database: Path) -> None:
    check_file(source_file)
    database.parent.mkdir(parents=True, exist_ok=True)
    source = sqlite3.connect(f"file:{source_file}?mode=ro", uri=True)
    destination = sqlite3.connect(database, timeout=30)
    try:
        source.backup(destination)
    finally:
        destination.close()
        source.close()
