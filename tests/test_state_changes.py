"""One owner per state change: every caller (page, API, script) of a change to a session's
data goes through the same check, and is refused the same way when the state forbids it."""

from __future__ import annotations

import pytest
from sqlmodel import select

from app.db import read_session, write_session
from app.lab.attempts import latest_attempt
from app.models import Attempt, LabSession, SessionStatus, Take
from app.review import grading
from app.web.i18n import translator
from tests.factories import (
    API,
    HEADING,
    browser,
    do_lab,
    post_form,
    post_json,
    review,
    save_manual,
    start,
    submit,
    token_for,
)


def data_rows(session_id: int) -> tuple[int, int, str]:
    """(takes, attempts, status): what a refused change must leave as it was."""
    with read_session() as db:
        takes = db.exec(select(Take).where(Take.session_id == session_id)).all()
        attempts = db.exec(select(Attempt).where(Attempt.session_id == session_id)).all()
        session = db.get(LabSession, session_id)
        return len(takes), len(attempts), session.status


def every_caller(client, auth, session_id: int) -> dict:
    """Each way a student (browser) or a device (API) changes a session's data."""
    page = f"/lab/sessions/{session_id}"
    api = f"{API}/sessions/{session_id}"
    csv_body = {"part": "heading", "text": "position_1\n" + "1.5\n" * 12}
    samples = {"samples": [1.5] * 12, "unit": "deg/h"}
    return {
        "typed": lambda: save_manual(client, session_id, "heading", HEADING),
        "csv": lambda: post_json(client, f"{page}/csv", csv_body, page),
        "trim page": lambda: post_json(
            client, f"{page}/trim", {"part": "heading", "position": 1, "trim": 1}, page
        ),
        "api put": lambda: client.put(f"{api}/heading/positions/1", json=samples, headers=auth),
        "api append": lambda: client.post(
            f"{api}/heading/positions/1/samples", json=samples, headers=auth
        ),
        "api trim": lambda: client.put(
            f"{api}/heading/positions/1/trim", json={"trim": 1}, headers=auth
        ),
        "api submit": lambda: client.post(f"{api}/submit", headers=auth),
    }


def every_form(client, session_id: int) -> dict:
    """The page forms that change a session (they answer with the page and a message)."""
    page = f"/lab/sessions/{session_id}"
    return {
        "order": lambda: post_form(client, f"{page}/order", {"symmetric": "on"}, page=page),
        "discussion": lambda: post_form(
            client, f"{page}/discussion", {"discussion": "Changed."}, page=page
        ),
        "submit": lambda: post_form(client, f"{page}/submit", page=page),
    }


@pytest.mark.parametrize("state", ["awaiting review", "graded"])
def test_every_caller_is_refused_the_same_way_when_the_work_cannot_change(world, state):
    student = browser(world, "s1")
    session_id = start(student, world)
    do_lab(student, session_id)
    submit(student, session_id)
    key = "lab.awaiting_review"
    if state == "graded":
        teacher = browser(world, "teacher1")
        assert review(teacher, session_id, points="80", action="release").status_code == 303
        key = "lab.already_graded"
    message = translator("en")(key)
    before = data_rows(session_id)
    auth = token_for(student, "s1")
    for name, call in every_caller(student, auth, session_id).items():
        reply = call()
        assert (reply.status_code, reply.json()["detail"]) == (409, message), name
    for name, call in every_form(student, session_id).items():
        reply = call()
        assert reply.status_code == 303, name
        shown = student.get(reply.headers["location"]).text
        assert message.replace("'", "&#39;") in shown, name
    assert data_rows(session_id) == before


def test_returning_and_releasing_as_a_script_would_do_all_their_effects(world):
    """The desk and bulk release call grading.*; a script calling them directly gets the
    same: the status, the attempt's dates and the student's notice."""
    student = browser(world, "s1")
    session_id = start(student, world)
    do_lab(student, session_id)
    submit(student, session_id)
    with write_session() as db:
        session = db.get(LabSession, session_id)
        attempt = latest_attempt(db, session_id)
        grading.return_for_revision(db, session, attempt)
    with read_session() as db:
        attempt = latest_attempt(db, session_id)
        assert db.get(LabSession, session_id).status == SessionStatus.returned
        assert attempt.returned_at is not None and attempt.seen_at is None
    assert 'id="revising-notice"' not in student.get(f"/lab/sessions/{session_id}").text
    assert "returned" in student.get("/").text
    # the student revises and submits again; the change reopened the work
    assert save_manual(student, session_id, "heading", HEADING).status_code == 200
    assert data_rows(session_id)[2] == SessionStatus.in_progress
    submit(student, session_id)
    with write_session() as db:
        session = db.get(LabSession, session_id)
        attempt = latest_attempt(db, session_id)
        attempt.points = 90.0
        grading.release(db, session, attempt)
    assert data_rows(session_id)[1:] == (2, SessionStatus.graded)
