"""Trips to the thread pool per request: each one hands the interpreter between the event
loop and a thread twice, which under a class's load is a wait (bench/README.md, issue 32)."""

from __future__ import annotations

import anyio.to_thread
import pytest

from tests.factories import (
    _form_token,
    browser,
    do_lab,
    new_session,
    post_json,
    start,
)


@pytest.fixture
def trips(monkeypatch) -> list[int]:
    counted = [0]
    run_sync = anyio.to_thread.run_sync

    async def counting(*args, **kwargs):
        counted[0] += 1
        return await run_sync(*args, **kwargs)

    monkeypatch.setattr(anyio.to_thread, "run_sync", counting)
    return counted


def test_the_database_session_costs_no_trip_to_make_nor_on_sqlite_to_close(
    student_client, trips, backend
):
    """results.json: the caller and their session, found in one trip (1), and the handler
    (1); the database session is made on the event loop, and closed there on SQLite (on
    PostgreSQL, a round trip to a server that may be elsewhere, in the pool: 1)."""
    session_id = new_session(student_client)
    page = f"/lab/sessions/{session_id}"
    saved = post_json(
        student_client,
        f"{page}/manual",
        {"part": "heading", "unit": "deg/h", "columns": {str(k): [1.0] * 10 for k in (1, 2)}},
        page=page,
    )
    assert saved.status_code == 200, saved.text
    trips[0] = 0
    assert student_client.get(f"{page}/results.json").status_code == 200
    assert trips[0] == (2 if backend == "sqlite" else 3)


def test_a_write_finds_its_caller_once(student_client, trips, backend):
    """A row write: the CSRF check finds the caller (1), the session's owner is checked in
    a snapshot (1: the caller already known, no trip of its own), the handler (1)."""
    session_id = new_session(student_client)
    page = f"/lab/sessions/{session_id}"
    token = _form_token(student_client, page)
    trips[0] = 0
    turned = student_client.post(
        f"{page}/turn",
        json={"part": "heading", "position": 2},
        headers={"X-CSRF-Token": token},
    )
    assert turned.status_code == 200, turned.text
    assert trips[0] == (3 if backend == "sqlite" else 4)


def test_a_teachers_page_finds_its_teacher_with_the_assignment(world, trips, backend):
    """The class dashboard: the teacher and their assignment in one trip (1), the handler
    (1); a role check alone never costs a trip (``accounts.deps.teacher_user``)."""
    student = browser(world, "s1")
    do_lab(student, start(student, world))
    teacher = browser(world, "teacher1")
    path = f"/courses/{world['course']}/assignments/{world['assignment']}"
    assert teacher.get(path).status_code == 200
    trips[0] = 0
    assert teacher.get(path).status_code == 200
    assert trips[0] == (2 if backend == "sqlite" else 3)
