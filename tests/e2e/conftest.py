"""A real uvicorn server on a free loopback port and Debian's Chromium driven by Playwright.

``live_server`` is one worker on a SQLite file; ``pg_live_server`` is two workers on a
PostgreSQL database (from the session's test server), the way a department runs it.

Browser tests skip when /usr/bin/chromium is missing -- except in CI (CI=true), where
they fail instead, so that CI can never pass without running them.
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from dataclasses import dataclass
from pathlib import Path

import httpx
import pytest

from tests.loopback import TLS

CHROMIUM = Path("/usr/bin/chromium")
ARTIFACTS = Path(__file__).resolve().parents[1] / "artifacts"
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-dev-shm-usage",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
    "--disable-quic",
    # V8's optimising compilers (Maglev, TurboFan) off: a test's pages live for seconds, too
    # short for optimised code to repay its compiling -- the browser tests' CPU 119 -> 112 s
    # (layout, charts, lab and editing flows on two workers, three runs against two)
    "--js-flags=--max-opt=1",
]
TEACHER_PASSWORD = "e2e-teacher-pass-1"
STUDENT_PASSWORD = "e2e-student-pass-1"


@dataclass
class LiveServer:
    url: str
    var_dir: Path
    env: dict
    process: subprocess.Popen | None = None
    database_url: str | None = None
    serve_args: tuple[str, ...] = ()

    def kill_9(self) -> None:
        """SIGKILL the server and all its workers at once (no shutdown code runs)."""
        assert self.process is not None
        os.killpg(self.process.pid, signal.SIGKILL)
        self.process.wait(10)

    def restarted(self):
        """The same installation served again (a context manager)."""
        return running_server(self.var_dir, *self.serve_args, database_url=self.database_url)

    def gyrolab(self, *args: str, stdin: str | None = None) -> subprocess.CompletedProcess:
        return subprocess.run(
            [sys.executable, "-m", "app.cli.main", *args],
            env=self.env,
            input=stdin,
            capture_output=True,
            text=True,
            check=True,
        )


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def server_env(var_dir: Path, database_url: str | None = None) -> dict:
    env = {**os.environ, "GYROLAB_VAR_DIR": str(var_dir)}
    env.pop("GYROLAB_DATABASE_URL", None)
    if database_url:
        env["GYROLAB_DATABASE_URL"] = database_url
    return env


@contextmanager
def running_server(
    var_dir: Path, *serve_args: str, database_url: str | None = None
) -> Iterator[LiveServer]:
    """``gyrolab serve`` in a subprocess (its own process group) on a free loopback port,
    stopped afterwards.

    A port found free can be taken by another process before the server binds it (seen
    once in CI: ``[Errno 98] Address already in use``); the server is then started again
    on another port, up to three times.
    """
    env = server_env(var_dir, database_url)
    log_path = var_dir / "server.log"
    for attempt in range(3):
        port = free_port()
        url = f"http://127.0.0.1:{port}"
        server = LiveServer(url, var_dir, env, None, database_url, serve_args)
        log_start = log_path.stat().st_size if log_path.exists() else 0
        with open(log_path, "a") as log:
            process = subprocess.Popen(
                [sys.executable, "-m", "app.cli.main", "serve", "--port", str(port), *serve_args],
                env=env,
                stdout=log,
                stderr=subprocess.STDOUT,
                start_new_session=True,
            )
        server.process = process
        try:
            if _wait_until_serving(server, log_path, log_start):
                break
        except BaseException:
            _stop(process)
            raise
        _stop(process)
        if attempt == 2:
            raise RuntimeError(log_path.read_text())
    try:
        yield server
    finally:
        _stop(process)


def _wait_until_serving(server: LiveServer, log_path: Path, log_start: int) -> bool:
    """True once the server answers; False if it exited because its port was taken."""
    deadline = time.monotonic() + 60
    with httpx.Client(timeout=1, verify=TLS) as client:
        while True:
            try:
                if client.get(f"{server.url}/login").status_code == 200:
                    return True
            except httpx.HTTPError:
                pass
            if server.process.poll() is not None or time.monotonic() > deadline:
                with open(log_path) as log:
                    log.seek(log_start)
                    if "Address already in use" in log.read():
                        return False
                raise RuntimeError(log_path.read_text())
            time.sleep(0.2)


def _stop(process: subprocess.Popen) -> None:
    process.terminate()
    with suppress(subprocess.TimeoutExpired):
        process.wait(10)
    with suppress(ProcessLookupError):  # workers the supervisor left behind
        os.killpg(process.pid, signal.SIGKILL)


def add_teacher_and_student(var_dir: Path, database_url: str | None = None) -> None:
    """A migrated installation with the accounts ``teacher`` and ``student`` (written here,
    in-process, rather than by two ``gyrolab create-user`` runs)."""
    from sqlmodel import Session

    from app.accounts.service import create_user
    from app.db import make_engine
    from app.migrate import upgrade_to_head
    from app.models import Role

    url = database_url or f"sqlite:///{var_dir / 'gyrolab.db'}"
    upgrade_to_head(url)
    engine = make_engine(url)
    try:
        with Session(engine) as db:
            for username, name, role, password in (
                ("teacher", "E2E Teacher 李老师", Role.teacher, TEACHER_PASSWORD),
                ("student", "E2E 学生", Role.student, STUDENT_PASSWORD),
            ):
                create_user(db, username=username, display_name=name, role=role, password=password)
            db.commit()
    finally:
        engine.dispose()


@contextmanager
def new_live_server(var_dir: Path, postgres=None) -> Iterator[LiveServer]:
    """An empty installation with one teacher and one student: one worker on a SQLite file,
    or (given the test PostgreSQL) two workers on a database of its own."""
    if postgres is None:
        add_teacher_and_student(var_dir)
        with running_server(var_dir, "--no-demo") as server:
            yield server
        return
    name, url = postgres.new_database()
    add_teacher_and_student(var_dir, url)
    try:
        with running_server(var_dir, "--no-demo", "--workers", "2", database_url=url) as server:
            yield server
    finally:
        postgres.server.drop_database(name)


@pytest.fixture(scope="session")
def live_server(tmp_path_factory) -> Iterator[LiveServer]:
    """One installation on SQLite for the whole run (tests add what they need to it)."""
    with new_live_server(tmp_path_factory.mktemp("live-var")) as server:
        yield server


@pytest.fixture(scope="session")
def pg_live_server(tmp_path_factory, postgres) -> Iterator[LiveServer]:
    """The same on PostgreSQL, served by two uvicorn workers, the way a department runs it."""
    with new_live_server(tmp_path_factory.mktemp("pg-live-var"), postgres) as server:
        yield server


@pytest.fixture(params=["sqlite", "postgresql"])
def any_live_server(request) -> LiveServer:
    """``live_server`` and ``pg_live_server`` in turn."""
    return request.getfixturevalue("live_server" if request.param == "sqlite" else "pg_live_server")


@pytest.fixture(scope="session")
def demo_server(tmp_path_factory) -> Iterator[tuple[LiveServer, dict[str, str]]]:
    """What a newcomer gets from the RUN command: demo accounts, class and submissions."""
    var_dir = tmp_path_factory.mktemp("demo-var")
    with running_server(var_dir) as server:
        lines = (var_dir / "demo-credentials.txt").read_text().splitlines()
        credentials = {
            line.split(",")[1]: line.split(",")[2] for line in lines if not line.startswith("#")
        }
        yield server, credentials


@pytest.fixture(scope="session")
def browser():
    if not CHROMIUM.exists():
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail("CI=true but /usr/bin/chromium is missing: browser tests must run in CI")
        pytest.skip("Debian's chromium is not installed (python3 dev.py test installs it)")
    from playwright.sync_api import expect, sync_playwright

    # the pages' own default (new_page sets 10 s) for expect's waits too: 5 s is short on a
    # CI machine whose two cores serve three test workers, their servers and browsers
    expect.set_options(timeout=10_000)
    with sync_playwright() as playwright:
        instance = playwright.chromium.launch(
            executable_path=str(CHROMIUM), headless=True, args=CHROMIUM_ARGS
        )
        yield instance
        instance.close()


AXE = None  # axe-core, loaded on first use (the wheel carries axe.min.js)
WCAG = {
    "runOnly": {"type": "tag", "values": ["wcag2a", "wcag2aa", "wcag21a", "wcag21aa", "wcag22aa"]},
    "resultTypes": ["violations"],
}


def axe_problems(page) -> list[tuple]:
    """axe-core's serious and critical WCAG A/AA violations on the page as it is now."""
    global AXE
    if AXE is None:
        from axe_playwright_python.sync_playwright import Axe

        AXE = Axe()
    found = AXE.run(page, options=WCAG).response["violations"]
    return [
        (v["id"], v["impact"], [node["target"] for node in v["nodes"][:3]])
        for v in found
        if v["impact"] in ("serious", "critical")
    ]


def log_in(page, url: str, username: str, password: str) -> None:
    page.goto(f"{url}/login")
    page.fill("input[name=username]", username)
    page.fill("input[name=password]", password)
    with page.expect_navigation():
        page.click("button[type=submit].primary")
    assert "/login" not in page.url, f"log-in as {username} failed"


# plotly.js (4.6 MB) is fetched and parsed when the first chart comes into view: 1.3 s on an
# idle machine, past expect's 5 s default on a CI machine busy with three test workers
CHART_TIMEOUT_MS = 30_000


def expect_chart_drawn(chart) -> None:
    """Scroll a `.chart` element into view and wait until plotly has drawn it."""
    from playwright.sync_api import expect

    chart.scroll_into_view_if_needed()
    expect(chart.locator(".main-svg").first).to_be_visible(timeout=CHART_TIMEOUT_MS)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item, call):
    report = yield
    if report.when == "call":
        item.rep_call = report
    return report


@pytest.fixture
def new_page(browser, request):
    """Open pages in fresh contexts (one per person); screenshots of failures are kept."""
    contexts = []
    violations: list[str] = []

    def open_page(locale: str = "en-US"):
        context = browser.new_context(locale=locale, viewport={"width": 1280, "height": 860})
        contexts.append(context)
        page = context.new_page()
        page.set_default_timeout(10_000)
        page.on(
            "console",
            lambda message: (
                violations.append(message.text)
                if "Content Security Policy" in message.text
                else None
            ),
        )
        page.on("pageerror", lambda error: violations.append(f"page error: {error}"))
        return page

    yield open_page
    report = getattr(request.node, "rep_call", None)
    if report is not None and report.failed:
        ARTIFACTS.mkdir(exist_ok=True)
        for index, context in enumerate(contexts):
            for number, page in enumerate(context.pages):
                name = f"{request.node.name}-{index}-{number}.png"
                page.screenshot(path=str(ARTIFACTS / name), full_page=True)
    for context in contexts:
        context.close()
    assert not violations, violations  # the CSP blocked something, or a script failed
