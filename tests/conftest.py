"""Shared fixtures: a fresh migrated database per test, an HTTP client, logged-in users.

Every test that touches the database runs twice: on a SQLite file and on a real PostgreSQL
server (``tests/pgserver.py``; one throw-away cluster per run). Either way each test gets
its own database copied from a template migrated once per run (a file copy on SQLite,
``CREATE DATABASE … TEMPLATE`` on PostgreSQL); a fixture whose world is expensive to build
(the route matrix's) builds it once per module and copies that the same way
(:func:`snapshot`).  Mark a test ``sqlite_only`` or ``postgres_only`` when it is about one
database itself.  PostgreSQL tests skip with the reason when the server cannot run here --
except in CI (CI=true), where they fail instead.

Passwords are hashed with argon2id's cheapest parameters here (the production parameters
are tested once, in test_auth.py): hashing is not what these tests test.
"""

from __future__ import annotations

import gc
import itertools
import os
import shutil
import sqlite3
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from app.accounts import security
from app.config import get_settings
from app.db import engine_for
from app.models import Role
from tests.factories import build_world, login, make_user
from tests.pgserver import ADMIN_URL_ENV, PostgresServer, PostgresUnavailable

BACKENDS = ("sqlite", "postgresql")
IN_CI = os.environ.get("CI", "").lower() == "true"
# the command line speaks the language LANG names: the tests expect English unless they ask
os.environ["LANG"] = "C.UTF-8"
PRODUCTION_ARGON2 = (
    security.ARGON2_MEMORY_KIB,
    security.ARGON2_TIME_COST,
    security.ARGON2_PARALLELISM,
)
# argon2's minimum: 8 KiB, one pass (a hash costs ~0.1 ms instead of ~40 ms)
security.ARGON2_MEMORY_KIB, security.ARGON2_TIME_COST, security.ARGON2_PARALLELISM = 8, 1, 1
security.password_hasher.cache_clear()


def pytest_collection_finish(session) -> None:
    """The collected modules' objects moved out of the garbage collector's sight, and its
    collections made rarer: a test process allocates millions of short-lived objects, and
    every third-generation collection walked the whole heap of imported code (17 % of the
    CPU of the API, lab and review tests; memory is not what these processes run short of)."""
    gc.collect()
    gc.freeze()
    gc.set_threshold(20_000, 20, 20)


def pytest_addoption(parser) -> None:
    parser.addoption(
        "--backends",
        default=",".join(BACKENDS),
        help="the databases to run database tests on (default: sqlite,postgresql)",
    )


def pytest_generate_tests(metafunc) -> None:
    """Run every database test on each backend (``sqlite_only`` and ``one_backend`` tests
    on SQLite alone)."""
    if "backend" in metafunc.fixturenames:
        chosen = metafunc.config.getoption("backends").split(",")
        backends = [name for name in BACKENDS if name in chosen]
        marked = metafunc.definition.get_closest_marker
        if marked("sqlite_only") or marked("one_backend"):
            backends = [name for name in backends if name == "sqlite"]
        if metafunc.definition.get_closest_marker("postgres_only"):
            backends = [name for name in backends if name == "postgresql"]
        metafunc.parametrize("backend", backends, indirect=True)


@dataclass
class PostgresForTests:
    server: PostgresServer
    template: str
    names: itertools.count

    def new_database(self) -> tuple[str, str]:
        """A fresh database at the newest schema: (name, SQLAlchemy URL)."""
        name = f"gyrolab_test_{os.getpid()}_{next(self.names)}"
        return name, self.server.create_database(name, template=self.template)


@pytest.fixture(scope="session")
def postgres(request) -> Iterator[PostgresForTests]:
    """A PostgreSQL server for this test run, with a migrated template database."""
    from app.migrate import upgrade_to_head

    if "postgresql" not in request.config.getoption("backends").split(","):
        pytest.skip("PostgreSQL is not among --backends")
    server = PostgresServer(os.environ.get(ADMIN_URL_ENV))
    try:
        server.start()
    except PostgresUnavailable as error:
        if IN_CI:
            pytest.fail(f"CI=true but PostgreSQL cannot run, and its tests must: {error}")
        pytest.skip(
            f"PostgreSQL tests skipped: {error}. `python3 dev.py test` installs Debian's "
            f"postgresql package when it may; or set {ADMIN_URL_ENV} to a server's admin URL."
        )
    template = f"gyrolab_template_{os.getpid()}"
    try:
        upgrade_to_head(server.create_database(template))
        yield PostgresForTests(server, template, itertools.count())
    finally:
        try:
            server.drop_database(template)
        finally:
            server.stop()


@pytest.fixture(scope="session")
def sqlite_template(tmp_path_factory) -> Path:
    """A SQLite file migrated to the newest schema, once per run."""
    from app.migrate import upgrade_to_head

    path = tmp_path_factory.mktemp("template") / "gyrolab.db"
    upgrade_to_head(f"sqlite:///{path}")
    with sqlite3.connect(path) as connection:  # everything in the main file, no -wal beside
        connection.execute("PRAGMA wal_checkpoint(TRUNCATE)")
    return path


@pytest.fixture
def backend(request) -> str:
    return request.param


@dataclass
class TestDatabase:
    """The database of one test: a SQLite file, or a PostgreSQL database by name."""

    backend: str
    path: Path | None = None
    name: str | None = None
    pg: PostgresForTests | None = None

    def close_connections(self) -> None:
        if engine_for.cache_info().currsize:
            engine_for(get_settings().database_url).dispose()
        engine_for.cache_clear()

    def copy_from(self, source: str | Path) -> None:
        """Replace this database by a copy of ``source`` (a file, or a database name)."""
        self.close_connections()
        if self.path is not None:
            for suffix in ("-wal", "-shm"):
                Path(f"{self.path}{suffix}").unlink(missing_ok=True)
            shutil.copyfile(source, self.path)
        else:
            self.pg.server.drop_database(self.name)
            self.pg.server.create_database(self.name, template=str(source))

    def copy_to(self, target: str | Path) -> None:
        """Save a copy of this database as ``target`` (a file, or a new database name)."""
        self.close_connections()
        if self.path is not None:
            with sqlite3.connect(self.path) as source, sqlite3.connect(target) as copy:
                source.backup(copy)
        else:
            self.pg.server.create_database(str(target), template=self.name)


@pytest.fixture
def test_database(tmp_path, monkeypatch, backend, request) -> Iterator[TestDatabase]:
    monkeypatch.setenv("GYROLAB_VAR_DIR", str(tmp_path / "var"))
    for name in ("GYROLAB_DATABASE_URL", "GYROLAB_SECRET_KEY"):
        monkeypatch.delenv(name, raising=False)
    if backend == "postgresql":
        pg: PostgresForTests = request.getfixturevalue("postgres")
        name, url = pg.new_database()
        monkeypatch.setenv("GYROLAB_DATABASE_URL", url)
        database = TestDatabase(backend, name=name, pg=pg)
    else:
        (tmp_path / "var").mkdir()
        path = tmp_path / "var" / "gyrolab.db"
        shutil.copyfile(request.getfixturevalue("sqlite_template"), path)
        database = TestDatabase(backend, path=path)
    get_settings.cache_clear()
    engine_for.cache_clear()
    forget_process_caches()
    yield database
    database.close_connections()
    get_settings.cache_clear()
    if database.name:
        pg.server.drop_database(database.name)


def forget_process_caches() -> None:
    """Each test starts like a fresh worker: no cached results, no leased rate windows."""
    from app.accounts.rate_leases import LEASES
    from app.lab.recent_samples import RECENT
    from app.lab.result_cache import CACHE, SUMMARIES
    from app.reports.pdf_cache import pdf_cache
    from app.review.take_summaries import TAKE_SUMMARIES

    CACHE.clear()
    RECENT.clear()
    SUMMARIES.clear()
    TAKE_SUMMARIES.clear()
    pdf_cache().clear()
    LEASES.clear()


@pytest.fixture
def var_dir(test_database) -> Path:
    return get_settings().var_dir


_APPS: dict = {}


@pytest.fixture
def app(var_dir):
    """The app, built once per test process: FastAPI builds each included router's routes
    when a request first reaches it, ~100 ms an app, which every test paid again.  Nothing
    in it belongs to one test: the settings it reads when built (the body limit) are every
    test's, the rest (database, secret key, var dir) is read per request or per start-up,
    and each test's client runs the start-up again."""
    from app.main import create_app

    key = get_settings().max_body_bytes
    if key not in _APPS:
        _APPS[key] = create_app(migrate_on_start=False)
    return _APPS[key]


@pytest.fixture(scope="module")
def snapshots() -> Iterator[dict]:
    """Worlds built once per module: {(name, backend): (copy, value, drop)} (see snapshot)."""
    saved: dict = {}
    yield saved
    for _copy, _value, drop in saved.values():
        drop()


def snapshot(request, name: str, build):
    """``build()``'s value, with the database as ``build`` left it: built in the first test
    of the module that asks (per backend), copied into the database of every later one."""
    database: TestDatabase = request.getfixturevalue("test_database")
    saved = request.getfixturevalue("snapshots")
    key = (name, database.backend)
    if key in saved:
        copy, value, _ = saved[key]
        database.copy_from(copy)
        return value
    value = build()
    if database.path is not None:
        copy = request.getfixturevalue("tmp_path_factory").mktemp("snapshot") / "gyrolab.db"
        drop = lambda: None  # noqa: E731  (the file goes with pytest's temporary directory)
    else:
        copy = f"{database.name}_{name}"
        drop = lambda: database.pg.server.drop_database(copy)  # noqa: E731
    database.copy_to(copy)
    saved[key] = (copy, value, drop)
    return value


@pytest.fixture
def client(app) -> Iterator[TestClient]:
    with TestClient(app, follow_redirects=False) as test_client:
        yield test_client


@pytest.fixture
def world(app, teacher) -> dict:
    """A course of teacher1 with students s1–s3 and an assignment (tests.factories)."""
    return build_world(app, teacher)


@pytest.fixture
def teacher():
    return make_user("teacher1", Role.teacher, name="Teacher One")


@pytest.fixture
def student():
    return make_user("student1", Role.student, name="张三")


@pytest.fixture
def teacher_client(client, teacher):
    assert login(client, "teacher1").status_code == 303
    return client


@pytest.fixture
def student_client(client, student):
    assert login(client, "student1").status_code == 303
    return client
