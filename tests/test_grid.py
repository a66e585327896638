"""Issue 34 item 5: saved readings come back into the typed grid for editing, and a
correction is a new take of that position alone, the old one kept."""

from __future__ import annotations

from sqlmodel import select

from app.db import read_session
from app.lab.grid import GRID_LIMIT
from app.models import Take
from tests.factories import handout, new_session, post_json, save_manual


def grid(client, session_id, part="heading"):
    response = client.get(f"/lab/sessions/{session_id}/grid.json", params={"part": part})
    assert response.status_code == 200, response.text
    return response.json()


def takes_of(session_id, position):
    with read_session() as db:
        statement = select(Take).where(
            Take.session_id == session_id, Take.part == "heading", Take.position == position
        )
        return db.exec(statement.order_by(Take.id)).all()


def test_saved_readings_come_back_as_typed_in_their_unit(student_client):
    session_id = new_session(student_client)
    typed = {k: [0.0029833 + 0.0000011 * i * k for i in range(12)] for k in (1, 2, 3, 4)}
    saved = save_manual(student_client, session_id, "heading", typed, unit="deg/s")
    assert saved.status_code == 200
    shown = grid(student_client, session_id)
    assert shown["unit"] == "deg/s"
    assert set(shown["positions"]) == {"1", "2", "3", "4"}
    for k, values in typed.items():
        entry = shown["positions"][str(k)]
        assert entry["source"] == "manual" and entry["n"] == 12
        # the unit's round trip (deg/s -> deg/h -> deg/s) leaves no 1e-16 tails behind
        assert entry["values"] == [float(f"{v:.12g}") for v in values]
    assert grid(student_client, session_id, "latitude") == {"unit": "deg/h", "positions": {}}


def test_positions_saved_in_different_units_are_shown_in_deg_per_hour(student_client):
    session_id = new_session(student_client)
    save_manual(student_client, session_id, "heading", {1: [0.004] * 10}, unit="deg/s")
    save_manual(student_client, session_id, "heading", {2: [-3.5] * 10})
    shown = grid(student_client, session_id)
    assert shown["unit"] == "deg/h"
    assert shown["positions"]["1"]["values"] == [14.4] * 10
    assert shown["positions"]["2"]["values"] == [-3.5] * 10


def test_a_trimmed_transient_and_a_long_run_are_not_put_in_the_grid(student_client):
    session_id = new_session(student_client)
    page = f"/lab/sessions/{session_id}"
    save_manual(student_client, session_id, "heading", {1: [30.0, 20.0] + [10.0] * 10})
    trim = {"part": "heading", "position": 1, "trim": 2}
    assert post_json(student_client, f"{page}/trim", trim, page).status_code == 200
    long_run = [10.0 + (i % 7) * 0.01 for i in range(GRID_LIMIT + 1)]
    save_manual(student_client, session_id, "heading", {2: long_run})
    shown = grid(student_client, session_id)["positions"]
    assert shown["1"] == {"n": 10, "source": "manual", "values": [10.0] * 10}
    assert shown["2"] == {"n": GRID_LIMIT + 1, "source": "manual", "values": None}


def test_a_corrected_column_is_a_new_take_and_the_old_one_is_kept(student_client):
    session_id = new_session(student_client)
    columns = handout("handout_horizontal.csv")
    save_manual(student_client, session_id, "heading", columns)
    corrected = list(grid(student_client, session_id)["positions"]["2"]["values"])
    corrected[3] += 1.0  # the typo fixed: the whole column is sent back, as the grid does
    assert save_manual(student_client, session_id, "heading", {2: corrected}).json() == {
        "saved": [2]
    }
    old, new = takes_of(session_id, 2)
    assert old.superseded_at is not None and new.superseded_at is None
    assert len(takes_of(session_id, 1)) == 1  # the other positions are untouched
    assert grid(student_client, session_id)["positions"]["2"]["values"] == corrected


def test_an_unknown_part_is_refused_in_words(student_client):
    session_id = new_session(student_client)
    response = student_client.get(
        f"/lab/sessions/{session_id}/grid.json?part=roof", headers={"Accept": "application/json"}
    )
    assert response.status_code == 422
    assert response.json()["detail"][0]["loc"] == ["query", "part"]
