"""The per-minute API rate without a database write per request: workers lease requests of
the window kept in the database, and together never admit more than the limit."""

from __future__ import annotations

from datetime import timedelta

from sqlmodel import select

from app.accounts import rate_leases
from app.accounts.rate_leases import MAX_LEASE, RateLeases
from app.accounts.tokens import _leaser, new_token
from app.db import statement_session, write_session
from app.models import ApiToken, utcnow
from app.web.signing import token_digest
from tests.factories import login


def a_token(student) -> tuple[str, int]:
    with write_session() as db:
        raw, record = new_token(db, student, kind="personal", name="bench")
        return token_digest(raw), record.id


def run(workers: list[RateLeases], pattern, requests: int, limit: int, token) -> tuple[int, int]:
    """Send ``requests`` through the workers chosen by ``pattern(i)``: (admitted, writes)."""
    digest, token_id = token
    admitted = writes = 0
    for i in range(requests):
        with statement_session() as db:
            lease = _leaser(db, ApiToken, token_id)

            def counted(size, now, lease=lease):
                nonlocal writes
                writes += 1
                return lease(size, now)

            admitted += workers[pattern(i)].admit(digest, limit, counted).admitted
    return admitted, writes


def test_two_workers_admit_exactly_the_limit_with_few_writes(app, student):
    token = a_token(student)
    admitted, writes = run([RateLeases(), RateLeases()], lambda i: i % 2, 700, 600, token)
    assert admitted == 600
    assert writes < 700 / 4  # most requests only read


def test_a_lease_left_unused_never_lets_another_worker_past_the_limit(app, student):
    token = a_token(student)
    # worker 0 serves the first 300 requests, worker 1 the rest: worker 0 may keep part of
    # its last lease, which no other worker may use
    admitted, _ = run([RateLeases(), RateLeases()], lambda i: int(i >= 300), 700, 600, token)
    assert 600 - (MAX_LEASE - 1) <= admitted <= 600


def test_leases_shrink_to_one_request_near_the_limit(app, student):
    token = a_token(student)
    workers = [RateLeases() for _ in range(3)]
    admitted, _ = run(workers, lambda i: (i * 7) % 3, 10, 3, token)
    assert admitted == 3


def test_a_new_window_admits_again(app, student, monkeypatch):
    token = a_token(student)
    worker = RateLeases()
    assert run([worker], lambda i: 0, 5, 3, token)[0] == 3
    later = utcnow() + timedelta(seconds=61)
    monkeypatch.setattr(rate_leases, "utcnow", lambda: later)
    assert run([worker], lambda i: 0, 5, 3, token)[0] == 3


def test_refused_requests_say_how_long_to_wait(app, student):
    digest, token_id = a_token(student)
    worker = RateLeases()
    with statement_session() as db:
        for _ in range(2):
            assert worker.admit(digest, 2, _leaser(db, ApiToken, token_id)).admitted
        refused = worker.admit(digest, 2, _leaser(db, ApiToken, token_id))
    assert not refused.admitted and 58 <= refused.retry_after <= 60


def test_cookie_api_calls_share_the_limit_and_a_revoked_token_stops_at_once(
    client, student, monkeypatch
):
    from app.config import get_settings

    monkeypatch.setattr(get_settings(), "api_rate_per_minute", 40)
    login(client, "student1")
    statuses = [client.get("/api/v1/me").status_code for _ in range(45)]
    assert statuses == [200] * 40 + [429] * 5
    client.cookies.clear()
    raw = client.post(
        "/api/v1/auth/token", data={"username": "student1", "password": "correct-horse-42"}
    ).json()["access_token"]
    headers = {"Authorization": f"Bearer {raw}"}
    assert client.get("/api/v1/me", headers=headers).status_code == 200  # leased a few
    with write_session() as db:
        for record in db.exec(select(ApiToken)).all():
            record.revoked_at = utcnow()
            db.add(record)
    assert client.get("/api/v1/me", headers=headers).status_code == 401
