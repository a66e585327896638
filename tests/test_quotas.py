"""Storage and request quotas, and pruning old re-recordings (never submitted data)."""

from __future__ import annotations

import subprocess
import sys
from datetime import timedelta

import pytest
from sqlmodel import select

from app.config import get_settings
from app.db import read_session, write_session
from app.lab.quota import storage_used
from app.models import Role, SampleChunk, Take, User, utcnow
from tests.factories import API, csrf_from, login, make_user, new_api_session, post_form, token_for


def put(client, auth, session_id, k, n, value=10.0):
    return client.put(
        f"{API}/sessions/{session_id}/heading/positions/{k}",
        json={"samples": [value] * n, "unit": "deg/h"},
        headers=auth,
    )


def test_storage_quota_refuses_with_413_and_stores_nothing(client, student, monkeypatch):
    monkeypatch.setenv("GYROLAB_STUDENT_STORAGE_MB", "1")
    get_settings.cache_clear()
    auth = token_for(client, "student1")
    session_id = new_api_session(client, auth)
    assert put(client, auth, session_id, 1, 100_000).status_code == 200  # 0.8 MB
    with read_session() as db:
        before = storage_used(db, db.exec(select(User.id)).first())
    full = put(client, auth, session_id, 2, 50_000)  # +0.4 MB > 1 MB
    assert full.status_code == 413 and "1 MB" in full.json()["detail"]
    appended = client.post(
        f"{API}/sessions/{session_id}/heading/positions/1/samples",
        json={"samples": [10.0] * 50_000},
        headers=auth,
    )
    assert appended.status_code == 413
    with read_session() as db:
        assert storage_used(db, db.exec(select(User.id)).first()) == before == 800_000


def test_cookie_api_calls_are_rate_limited(client, student, monkeypatch):
    monkeypatch.setenv("GYROLAB_API_RATE_PER_MINUTE", "5")
    get_settings.cache_clear()
    login(client, "student1")
    statuses = [client.get(f"{API}/me").status_code for _ in range(7)]
    assert statuses == [200] * 5 + [429] * 2
    refused = client.get(f"{API}/me")
    assert 1 <= int(refused.headers["Retry-After"]) <= 60
    assert "slow down" in refused.json()["detail"]


def superseded_takes(client, auth, session_id) -> None:
    for _ in range(3):  # three takes of position 1: two superseded
        assert put(client, auth, session_id, 1, 10).status_code == 200


def age_superseded(days: int) -> None:
    with write_session() as db:
        for take in db.exec(select(Take).where(Take.superseded_at.is_not(None))).all():
            take.superseded_at = utcnow() - timedelta(days=days)
            db.add(take)


def test_prune_removes_old_re_recordings_but_never_submitted_data(client, student):
    from app.lab.prune import prune_takes

    auth = token_for(client, "student1")
    session_id = new_api_session(client, auth)
    for k in (1, 2, 3):
        assert put(client, auth, session_id, k, 10, value=10.0 + k).status_code == 200
    assert client.post(f"{API}/sessions/{session_id}/submit", headers=auth).status_code == 200
    superseded_takes(client, auth, session_id)  # supersedes the submitted take, then two more
    age_superseded(40)
    with write_session() as db:
        assert prune_takes(db, 60).takes == 0  # not old enough
    with write_session() as db:
        pruned = prune_takes(db, 30)
    assert pruned.takes == 2 and pruned.bytes == 160
    with read_session() as db:
        takes = db.exec(select(Take)).all()
        assert len(takes) == 4  # the 3 submitted (frozen) takes and the current one
        assert sum(t.frozen for t in takes) == 3
        assert all(
            db.exec(select(SampleChunk).where(SampleChunk.take_id == t.id)).first() for t in takes
        )
    results = client.get(f"{API}/sessions/{session_id}/results", headers=auth)
    assert results.status_code == 200


@pytest.mark.slow
def test_prune_from_the_command_line_and_the_admin_page(app, client, student):
    auth = token_for(client, "student1")
    session_id = new_api_session(client, auth)
    superseded_takes(client, auth, session_id)
    age_superseded(40)
    result = subprocess.run(
        [sys.executable, "-m", "app.cli.main", "prune", "--days", "30"],
        capture_output=True,
        text=True,
    )
    assert result.returncode == 0 and "removed 2 re-recording(s)" in result.stdout
    superseded_takes(client, auth, session_id)
    age_superseded(40)
    make_user("root", Role.admin)
    from fastapi.testclient import TestClient

    with TestClient(app, follow_redirects=False) as admin:
        login(admin, "root")
        response = post_form(admin, "/admin/prune", {"days": "30"}, page="/admin/accounts")
        assert response.status_code == 303
        assert "Removed 3 old recordings replaced" in admin.get("/admin/accounts").text
        teacher = make_user("t9", Role.teacher)
        assert teacher
    with TestClient(app, follow_redirects=False) as other:
        login(other, "t9")
        token = csrf_from(other, "/")
        assert other.post("/admin/prune", data={"csrf_token": token}).status_code == 403


@pytest.mark.one_backend  # input refused before any write
@pytest.mark.parametrize("days", ["0", "-1", "x", "99999"])
def test_prune_days_are_checked(app, days):
    make_user("root", Role.admin)
    from fastapi.testclient import TestClient

    with TestClient(app, follow_redirects=False) as admin:
        login(admin, "root")
        response = post_form(admin, "/admin/prune", {"days": days}, page="/admin/accounts")
        assert response.status_code == 400
