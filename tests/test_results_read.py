"""Issue 32: the results endpoint's hot path (``lab.results_read``) answers exactly what the
general path answers, and only when the general path would answer 200 with the same body."""

from __future__ import annotations

import pytest
from sqlmodel import select

from app.accounts.security import revoke_credentials
from app.db import write_session
from app.lab import result_cache
from app.lab import results_read as fast
from app.models import ApiToken, LabSession, SessionMember, User
from tests.factories import browser, do_lab, start, token_for


@pytest.fixture
def fast_answers(monkeypatch) -> list[bool]:
    """Whether each results request was answered by the hot path."""
    answers: list[bool] = []
    found = fast.cached_results_for_token

    def recorded(*args):
        entry = found(*args)
        answers.append(entry is not None)
        return entry

    monkeypatch.setattr("app.lab.api.cached_results_for_token", recorded)
    return answers


def user_id(username: str) -> int:
    with write_session() as db:
        return db.exec(select(User.id).where(User.username == username)).one()


def test_the_hot_path_serves_the_cached_body_to_owner_and_partner(client, world, fast_answers):
    s1 = browser(world, "s1")
    session_id = start(s1, world)
    do_lab(s1, session_id)
    partner_id = user_id("s2")
    with write_session() as db:
        db.add(SessionMember(session_id=session_id, user_id=partner_id))
    url = f"/api/v1/sessions/{session_id}/results"
    owner, partner = token_for(client, "s1"), token_for(client, "s2")

    result_cache.CACHE.clear()
    first = client.get(url, headers=owner)  # a miss: solved on the general path
    assert first.status_code == 200 and fast_answers == [False]
    again = client.get(url, headers=owner)
    shared = client.get(url, headers=partner)
    assert fast_answers == [False, True, True]
    assert again.content == first.content == shared.content
    assert again.headers["content-type"] == "application/json"

    # a change of the data is a new key: the hot path misses, the general path solves
    with write_session() as db:
        db.get(LabSession, session_id).latitude_deg = 45.0
    changed = client.get(url, headers=owner)
    assert fast_answers[-1] is False and changed.content != first.content
    assert client.get(url, headers=owner).content == changed.content
    assert fast_answers[-1] is True


def test_the_hot_path_answers_nobody_the_general_path_refuses(client, world, fast_answers):
    s1 = browser(world, "s1")
    session_id = start(s1, world)
    do_lab(s1, session_id)
    url = f"/api/v1/sessions/{session_id}/results"
    owner, stranger = token_for(client, "s1"), token_for(client, "s3")
    assert client.get(url, headers=owner).status_code == 200
    assert client.get(url, headers=owner).status_code == 200
    assert fast_answers[-1] is True  # cached now

    assert client.get(url, headers=stranger).status_code == 404
    assert client.get(url, headers={"Authorization": "Bearer nonsense"}).status_code == 401
    assert client.get(url).status_code == 401
    assert (
        client.get(f"/api/v1/sessions/{session_id + 99}/results", headers=owner).status_code == 404
    )
    assert fast_answers[-4:] == [False] * 4

    owner_id = user_id("s1")
    with write_session() as db:  # a password change revokes every token: seen at once
        revoke_credentials(db, owner_id)
    assert client.get(url, headers=owner).status_code == 401
    assert fast_answers[-1] is False


def test_a_revoked_or_expired_token_and_a_forced_password_change_are_seen_at_once(
    client, world, fast_answers
):
    s1 = browser(world, "s1")
    session_id = start(s1, world)
    do_lab(s1, session_id)
    url = f"/api/v1/sessions/{session_id}/results"
    owner = token_for(client, "s1")
    client.get(url, headers=owner)
    assert client.get(url, headers=owner).status_code == 200 and fast_answers[-1]

    owner_id = user_id("s1")
    with write_session() as db:
        db.get(User, owner_id).must_change_password = True
    assert client.get(url, headers=owner).status_code == 403
    with write_session() as db:
        db.get(User, owner_id).must_change_password = False
        token = db.exec(select(ApiToken).where(ApiToken.user_id == owner_id)).one()
        token.revoked_at = token.created_at
    assert client.get(url, headers=owner).status_code == 401
    assert fast_answers[-2:] == [False, False]
