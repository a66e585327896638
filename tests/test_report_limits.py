"""Issue 31, item 2 (in part): PDF renders are bounded per process and per person; past
the limit a clear answer with Retry-After, and the slot comes back after every render."""

from __future__ import annotations

import pytest

from app.web.work_slots import pool
from tests.factories import new_session


@pytest.mark.one_backend
def test_a_second_render_of_the_same_person_waits_its_turn(student_client, monkeypatch):
    session_id = new_session(student_client)
    url = f"/lab/sessions/{session_id}/report.pdf"
    first = student_client.get(url)
    assert first.status_code == 200 and first.content.startswith(b"%PDF")
    assert not pool("reports").people  # the slot came back
    from app.db import read_session
    from app.models import LabSession

    with read_session() as db:
        owner = db.get(LabSession, session_id).owner_id
    pool("reports").take(owner)
    try:
        busy = student_client.get(url)
        assert busy.status_code == 429 and busy.headers["retry-after"] == "5"
        assert "still being made" in busy.text
    finally:
        pool("reports").give_back(owner)
    assert student_client.get(url).status_code == 200


@pytest.mark.one_backend
def test_the_process_renders_at_most_so_many_at_once(student_client, monkeypatch):
    session_id = new_session(student_client)
    url = f"/lab/sessions/{session_id}/report.pdf"
    others = [10_001, 10_002]  # two renders of other people under way
    for other in others:
        pool("reports").take(other)
    try:
        busy = student_client.get(url, headers={"Accept": "application/json"})
        assert busy.status_code == 503 and busy.headers["retry-after"] == "10"
        assert "making other reports" in busy.json()["detail"]
    finally:
        for other in others:
            pool("reports").give_back(other)
    assert student_client.get(url).status_code == 200
