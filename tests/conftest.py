"""Shared fixtures: a fresh migrated database per test, an HTTP client, login helpers.

Every test that touches the database runs twice: on a SQLite file and on a real PostgreSQL
server (``tests/pgserver.py``; one throw-away cluster per run, one database per test cloned
from a migrated template). Mark a test ``sqlite_only`` or ``postgres_only`` when it is
about one database itself.
PostgreSQL tests skip with the reason when the server cannot run here -- except in CI
(CI=true), where they fail instead.
"""

from __future__ import annotations

import itertools
import os
import re
from collections.abc import Iterator
from dataclasses import dataclass

import pytest
from fastapi.testclient import TestClient

from app.config import get_settings
from app.db import engine_for, write_session
from app.models import Role, User
from tests.pgserver import ADMIN_URL_ENV, PostgresServer, PostgresUnavailable

CSRF_RE = re.compile(r'name="csrf_token" value="([^"]+)"')
PASSWORD = "correct-horse-42"
BACKENDS = ("sqlite", "postgresql")
IN_CI = os.environ.get("CI", "").lower() == "true"


def pytest_generate_tests(metafunc) -> None:
    """Run every database test on each backend (``sqlite_only`` tests on SQLite alone)."""
    if "backend" in metafunc.fixturenames:
        backends = BACKENDS
        if metafunc.definition.get_closest_marker("sqlite_only"):
            backends = ("sqlite",)
        if metafunc.definition.get_closest_marker("postgres_only"):
            backends = ("postgresql",)
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
def postgres() -> Iterator[PostgresForTests]:
    """A PostgreSQL server for this test run, with a migrated template database."""
    from app.migrate import upgrade_to_head

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


@pytest.fixture
def backend(request) -> str:
    return request.param


@pytest.fixture
def var_dir(tmp_path, monkeypatch, backend, request) -> Iterator:
    monkeypatch.setenv("GYROLAB_VAR_DIR", str(tmp_path / "var"))
    for name in ("GYROLAB_DATABASE_URL", "GYROLAB_SECRET_KEY"):
        monkeypatch.delenv(name, raising=False)
    database = None
    if backend == "postgresql":
        pg: PostgresForTests = request.getfixturevalue("postgres")
        database, url = pg.new_database()
        monkeypatch.setenv("GYROLAB_DATABASE_URL", url)
    get_settings.cache_clear()
    engine_for.cache_clear()
    yield tmp_path / "var"
    if engine_for.cache_info().currsize:
        engine_for(get_settings().database_url).dispose()
    get_settings.cache_clear()
    engine_for.cache_clear()
    if database:
        pg.server.drop_database(database)


@pytest.fixture
def app(var_dir):
    from app.main import create_app
    from app.migrate import upgrade_to_head

    upgrade_to_head()
    return create_app(migrate_on_start=False)


@pytest.fixture
def client(app) -> Iterator[TestClient]:
    with TestClient(app, follow_redirects=False) as test_client:
        yield test_client


def make_user(
    username: str,
    role: Role = Role.student,
    *,
    must_change: bool = False,
    name: str = "",
    created_by: User | None = None,
) -> User:
    """An account with the password PASSWORD (``created_by``: the teacher whose roster made it)."""
    from app.accounts.service import create_user

    with write_session() as db:
        return create_user(
            db,
            username=username,
            display_name=name or username.title(),
            role=role,
            password=PASSWORD,
            must_change_password=must_change,
            created_by=created_by,
        )


def make_course(teacher: User, name: str = "Lab", students: tuple[User, ...] = ()) -> int:
    from app.accounts.service import enroll
    from app.models import Course

    with write_session() as db:
        course = Course(name=name, teacher_id=teacher.id)
        db.add(course)
        db.flush()
        for student in students:
            enroll(db, course, student)
        return course.id


HIDDEN_INPUT_RE = re.compile(r'<input type="hidden"[^>]*>')


def without_tokens(page: str) -> str:
    """The page without its hidden inputs, where random CSRF tokens live: a test that a
    short string is absent must not fail when a random token happens to contain it."""
    return HIDDEN_INPUT_RE.sub("", page)


def csrf_from(client: TestClient, path: str) -> str:
    response = client.get(path)
    match = CSRF_RE.search(response.text)
    assert match, f"no CSRF token on {path} ({response.status_code})"
    return match.group(1)


def login(client: TestClient, username: str, password: str = PASSWORD, next: str = "/"):
    token = csrf_from(client, "/login")
    return client.post(
        "/login",
        data={"username": username, "password": password, "csrf_token": token, "next": next},
    )


def post_form(client: TestClient, path: str, data: dict | None = None, files=None, page="/"):
    """POST a form the way the browser does: with the CSRF token from a page."""
    token = csrf_from(client, page)
    return client.post(path, data={**(data or {}), "csrf_token": token}, files=files)


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


def iter_routes(routes) -> Iterator:
    """Every APIRoute/WebSocket route, looking inside included routers (any FastAPI version)."""
    for route in routes:
        inner = getattr(route, "original_router", None)
        if inner is not None:
            yield from iter_routes(inner.routes)
        else:
            yield route
