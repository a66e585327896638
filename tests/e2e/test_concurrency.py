"""Concurrency on a real server, SQLite (one worker) and PostgreSQL (two workers):

* a writer waiting for the database's write lock never stops the event loop, so pages and
  streams of other users go on (found by the load test: database calls in ``async def``
  dependencies froze the whole worker until SQLite's busy timeout);
* guesses sent in parallel cannot get past the log-in throttle while passwords are hashed
  outside the write lock;
* the per-token rate limit holds across workers (leased from the database's window).
"""

from __future__ import annotations

import sqlite3
import threading
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager

import httpx
import pytest
from sqlalchemy import create_engine, text

from app.accounts.rate_leases import MAX_LEASE
from app.db import WRITE_LOCK_KEY
from tests.e2e.conftest import STUDENT_PASSWORD, LiveServer
from tests.loopback import TLS

pytestmark = pytest.mark.e2e


@contextmanager
def write_lock_held(server: LiveServer):
    """Hold the app's write lock from outside, as a long write transaction would."""
    if server.database_url is None:
        connection = sqlite3.connect(server.var_dir / "gyrolab.db", isolation_level=None)
        connection.execute("BEGIN IMMEDIATE")
        try:
            yield
        finally:
            connection.execute("ROLLBACK")
            connection.close()
        return
    engine = create_engine(server.database_url)
    with engine.connect() as connection:
        connection.execute(text(f"SELECT pg_advisory_xact_lock({WRITE_LOCK_KEY})"))
        try:
            yield
        finally:
            connection.rollback()
    engine.dispose()


def cookie_login(url: str, username: str, password: str) -> tuple[httpx.Client, str]:
    client = httpx.Client(base_url=url, timeout=30, verify=TLS)
    page = client.get("/login")
    token = page.text.split('name="csrf_token" value="')[1].split('"')[0]
    reply = client.post(
        "/login", data={"username": username, "password": password, "csrf_token": token}
    )
    assert reply.status_code == 303
    lab = client.get("/lab")
    return client, lab.text.split('name="csrf_token" value="')[1].split('"')[0]


def bearer(url: str) -> httpx.Client:
    client = httpx.Client(base_url=url, timeout=30, verify=TLS)
    reply = client.post(
        "/api/v1/auth/token", data={"username": "student", "password": STUDENT_PASSWORD}
    )
    client.headers["Authorization"] = f"Bearer {reply.json()['access_token']}"
    return client


def test_waiting_writers_do_not_stop_other_requests(any_live_server: LiveServer):
    url = any_live_server.url
    browser, csrf = cookie_login(url, "student", STUDENT_PASSWORD)
    api = bearer(url)
    session_id = api.post(
        "/api/v1/sessions",
        json={"title": "lock", "station": {"latitude_deg": 39.93, "earth_rate_deg_h": 15.04}},
    ).json()["id"]
    finished: dict[str, int] = {}

    def form_post() -> None:  # cookie + CSRF form: the CSRF check reads the login
        reply = browser.post("/lab/sessions", data={"station": "handout", "csrf_token": csrf})
        finished["form"] = reply.status_code

    def upload() -> None:  # bearer token + body: the token check and the store
        reply = api.put(
            f"/api/v1/sessions/{session_id}/heading/positions/1",
            json={"samples": [10.0 + i / 100 for i in range(20)]},
        )
        finished["upload"] = reply.status_code

    with write_lock_held(any_live_server):
        writers = [threading.Thread(target=form_post), threading.Thread(target=upload)]
        for writer in writers:
            writer.start()
        writers[0].join(1.0)  # give them time to reach the lock
        # Every worker must still answer while both writers wait for the lock.
        for _ in range(4):
            assert httpx.get(f"{url}/login", timeout=5, verify=TLS).status_code == 200
        assert finished == {}, "a write got through while the lock was held"
    for writer in writers:
        writer.join(30)
    assert finished == {"form": 303, "upload": 200}


def test_more_waiting_writers_than_pool_threads_all_get_through(any_live_server: LiveServer):
    """Fifty form posts (more than the 40 pool threads) queue on the write lock; when it
    is released every one completes.  A transaction held from the CSRF check into the
    handler used to need a free pool thread while all of them waited for its lock: SQLite
    answered 500 after its busy timeout, PostgreSQL would have waited for ever."""
    url = any_live_server.url
    browser, csrf = cookie_login(url, "student", STUDENT_PASSWORD)
    browser.timeout = httpx.Timeout(60)

    def form_post(_: int) -> int:
        reply = browser.post("/lab/sessions", data={"station": "handout", "csrf_token": csrf})
        return reply.status_code

    with ThreadPoolExecutor(50) as pool:
        with write_lock_held(any_live_server):
            replies = [pool.submit(form_post, i) for i in range(50)]
            threading.Event().wait(1.5)  # let every request reach the lock
        statuses = [reply.result(timeout=90) for reply in replies]
    assert statuses == [303] * 50


def test_parallel_guesses_cannot_pass_the_throttle(any_live_server: LiveServer):
    """Twelve wrong passwords at once from one address: each is charged before its hash, so
    at most five are checked (the per-account-and-address limit, 401) and the rest are
    refused (429).  (An account that does not exist is charged the same way; using one
    keeps the shared server's real accounts free of the lock.)  How many of the five are
    reached depends on timing: once two have completed as failures the growing delay
    refuses the rest sooner."""
    url = any_live_server.url

    def guess(i: int) -> int:
        return httpx.post(
            f"{url}/api/v1/auth/token",
            data={"username": "guessed-teacher", "password": f"wrong-guess-{i}"},
            timeout=60,
            verify=TLS,
        ).status_code

    with ThreadPoolExecutor(12) as pool:
        statuses = sorted(pool.map(guess, range(12)))
    assert set(statuses) <= {401, 429}
    assert 2 <= statuses.count(401) <= 5


def test_parallel_log_ins_of_one_account_all_get_through(any_live_server: LiveServer):
    """A script's workers logging in to one account at once from one address: attempts
    in flight are not failures, so none is slowed down (up to the five attempts per
    account and address that may be in flight at once, so parallel guesses stay bounded)."""
    url = any_live_server.url
    password = STUDENT_PASSWORD

    def token(_: int) -> int:
        return httpx.post(
            f"{url}/api/v1/auth/token",
            data={"username": "student", "password": password},
            timeout=60,
            verify=TLS,
        ).status_code

    with ThreadPoolExecutor(5) as pool:
        assert list(pool.map(token, range(5))) == [200] * 5


def test_token_rate_limit_holds_across_workers(any_live_server: LiveServer):
    """600 requests per minute per token: both workers lease requests of the one window in
    the database and never admit more; a worker's unused lease (at most MAX_LEASE - 1
    requests each) is the only slack."""
    api = bearer(any_live_server.url)
    with ThreadPoolExecutor(8) as pool:
        statuses = list(pool.map(lambda _: api.get("/api/v1/me").status_code, range(640)))
    slack = 2 * (MAX_LEASE - 1) if any_live_server.database_url else 0
    assert 600 - slack <= statuses.count(200) <= 600, statuses
    assert statuses.count(200) + statuses.count(429) == 640


def test_one_batch_sent_at_once_by_many_is_stored_once(any_live_server: LiveServer):
    """The append's offset check is a read-check-write: eight identical batches (offset 0)
    at once through both workers store ten samples, not eighty."""
    api = bearer(any_live_server.url)
    session = api.post(
        "/api/v1/sessions", json={"title": "offsets", "station": {"latitude_deg": 39.9}}
    ).json()["id"]
    batch = {"samples": [10.0 + i / 100 for i in range(10)], "offset": 0}
    path = f"/api/v1/sessions/{session}/heading/positions/1/samples"
    with ThreadPoolExecutor(8) as pool:
        replies = list(pool.map(lambda _: api.post(path, json=batch), range(8)))
    assert [reply.status_code for reply in replies] == [200] * 8
    assert sorted(reply.json()["added"] for reply in replies) == [0] * 7 + [10]
    stored = api.get(f"/api/v1/sessions/{session}").json()["positions"]
    assert [p["n_samples"] for p in stored] == [10]


@pytest.mark.postgres_only
def test_a_locked_lab_session_holds_up_only_its_own_writes(pg_live_server: LiveServer):
    """A write transaction on one lab session (its row locked, as a long save would) does
    not stop another student's save: per-row locks, not one lock for the database."""
    api = bearer(pg_live_server.url)
    body = {"title": "rows", "station": {"latitude_deg": 39.9}}
    locked, free = (api.post("/api/v1/sessions", json=body).json()["id"] for _ in range(2))
    samples = {"samples": [10.0] * 10}
    engine = create_engine(pg_live_server.database_url)
    finished: dict[int, int] = {}

    def save(session: int) -> None:
        path = f"/api/v1/sessions/{session}/heading/positions/1"
        finished[session] = api.put(path, json=samples, timeout=60).status_code

    with engine.connect() as connection:
        connection.execute(text(f"SELECT id FROM lab_session WHERE id = {locked} FOR UPDATE"))
        waiting = threading.Thread(target=save, args=(locked,))
        waiting.start()
        save(free)  # goes through while the other session is locked
        assert finished == {free: 200}
        connection.rollback()
    waiting.join(30)
    engine.dispose()
    assert finished == {free: 200, locked: 200}
