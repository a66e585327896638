"""Trimming the start of a recording: stored as a trim, never by deleting samples; the
result, the page, the exports and the API all use the same readings."""

from __future__ import annotations

import json

import numpy as np
import pytest
from sqlmodel import select

from app.db import read_session
from app.lab.store import load_samples
from app.models import Attempt, LabSession, Take
from tests.factories import (
    csrf_from,
    handout,
    new_session,
    post_json,
    save_manual,
    token_for,
)


def with_transient(columns: dict[int, list[float]], size: float = 1.5) -> dict:
    """Each position's readings behind five readings still swinging after the turn (a
    different swing at each position, so that it does not cancel into the bias)."""
    return {
        k: [v[0] + size * k * (5 - i) / 5 for i in range(5)] + list(v) for k, v in columns.items()
    }


def trim(client, session_id, position, count, part="heading"):
    page = f"/lab/sessions/{session_id}"
    body = {"part": part, "position": position, "trim": count}
    return post_json(client, f"{page}/trim", body, page)


def results(client, session_id) -> dict:
    return client.get(f"/lab/sessions/{session_id}/results.json").json()


def current(session_id: int, position: int) -> Take:
    with read_session() as db:
        return db.exec(
            select(Take).where(
                Take.session_id == session_id,
                Take.part == "heading",
                Take.position == position,
                Take.superseded_at.is_(None),
            )
        ).one()


def test_trimming_the_transient_restores_the_handouts_result(student_client):
    session_id = new_session(student_client)
    clean = handout("handout_horizontal.csv")
    save_manual(student_client, session_id, "heading", with_transient(clean))
    spoilt = results(student_client, session_id)["heading"]["theta_deg"]
    for position in (1, 2, 3, 4):
        assert trim(student_client, session_id, position, 5).status_code == 200
    theta = results(student_client, session_id)["heading"]["theta_deg"]
    assert theta == pytest.approx(-10.753, abs=1e-3) and abs(spoilt - theta) > 0.1
    # nothing deleted: all 15 readings stored, the first 5 marked
    take = current(session_id, 1)
    with read_session() as db:
        values, _ = load_samples(db, take)
    assert take.trim_start == 5 and values.size == take.n_samples == 15
    page = student_client.get(f"/lab/sessions/{session_id}").text
    assert "(5 trimmed)" in page
    # the CSV lists the readings used (and says what was left out); JSON keeps everything
    text = student_client.get(f"/lab/sessions/{session_id}/export.csv").content.decode("utf-8-sig")
    assert "the first 5 readings (the transient after turning) are trimmed" in text
    heading_rows = [line for line in text.splitlines() if line.startswith("heading,1,")]
    assert len(heading_rows) == 10
    document = student_client.get(f"/lab/sessions/{session_id}/export.json").json()
    first = document["positions"][0]
    assert first["trim_start"] == 5 and len(first["values_deg_h"]) == 15
    assert document["results"]["heading"]["theta_deg"] == pytest.approx(theta)
    # and 0 restores them
    trim(student_client, session_id, 1, 0)
    assert current(session_id, 1).trim_start == 0


@pytest.mark.one_backend  # input refused before any write
@pytest.mark.parametrize(
    ("count", "message"),
    [(15, "between 0 and 14"), (-1, ""), (6, "Only 9 readings would remain; at least 10")],
)
def test_a_trim_must_leave_enough_readings(student_client, count, message):
    session_id = new_session(student_client)
    save_manual(
        student_client, session_id, "heading", with_transient(handout("handout_horizontal.csv"))
    )
    response = trim(student_client, session_id, 1, count)
    assert 400 <= response.status_code < 500
    assert message in str(response.json()["detail"])
    assert current(session_id, 1).trim_start == 0


def test_nothing_to_trim_and_hostile_bodies(student_client):
    session_id = new_session(student_client)
    assert "no recording yet" in trim(student_client, session_id, 2, 1).json()["detail"]
    page = f"/lab/sessions/{session_id}"
    for body in ({"part": "heading", "position": 9, "trim": 1}, {"part": "x", "position": 1}):
        assert post_json(student_client, f"{page}/trim", body, page).status_code == 422
    token = csrf_from(student_client, page)
    assert student_client.post(f"{page}/trim", json={"part": "heading"}).status_code == 403
    assert token


def test_a_submitted_take_is_copied_never_changed(world):
    from tests.factories import browser, start, submit

    student = browser(world, "s1")
    session_id = start(student, world)
    save_manual(student, session_id, "heading", with_transient(handout("handout_horizontal.csv")))
    save_manual(student, session_id, "latitude", handout("handout_vertical.csv"))
    submit(student, session_id)
    frozen = current(session_id, 1)
    # awaiting review: no change
    assert trim(student, session_id, 1, 5).status_code == 409
    with read_session() as db:
        db.get(LabSession, session_id)
    from tests.factories import review

    review(browser(world, "teacher1"), session_id, action="return")
    assert trim(student, session_id, 1, 5).status_code == 200
    copy = current(session_id, 1)
    assert copy.id != frozen.id and copy.trim_start == 5
    with read_session() as db:
        assert db.get(Take, frozen.id).trim_start == 0  # the attempt's take is untouched
        assert db.get(LabSession, session_id).status == "in_progress"
        attempt = db.exec(select(Attempt)).one()
    assert str(frozen.id) in attempt.take_ids.split(",")


def test_the_api_trims_too(client, student):
    auth = token_for(client, "student1")
    created = client.post(
        "/api/v1/sessions",
        json={"title": "api", "station": {"latitude_deg": 39.93}},
        headers=auth,
    )
    session_id = created.json()["id"]
    values = [40.0, 30.0] + list(np.full(10, 10.5))
    put = client.put(
        f"/api/v1/sessions/{session_id}/heading/positions/1", json={"samples": values}, headers=auth
    )
    assert put.status_code == 200, put.text
    response = client.put(
        f"/api/v1/sessions/{session_id}/heading/positions/1/trim", json={"trim": 2}, headers=auth
    )
    assert response.json() == {
        "part": "heading",
        "position": 1,
        "n_samples": 12,
        "trim_start": 2,
        "n_used": 10,
    }
    bad = client.put(
        f"/api/v1/sessions/{session_id}/heading/positions/1/trim", json={"trim": 3}, headers=auth
    )
    assert bad.status_code == 400 and "Only 9 readings" in bad.json()["detail"]
    assert json.loads(json.dumps(bad.json()))["key"] == "lab.trim_too_much"
