"""Student lab over HTTP and WebSocket: every input method, bad input, submit, export."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from sqlmodel import func, select

from app.core.readings import parse_readings_csv
from app.core.sinusoid import elevation_angles, heading_angles
from app.core.solve import solve_heading, solve_latitude
from app.db import read_session, write_session
from app.lab.samples import unpack
from app.models import Assignment, Attempt, LabSession, Role, SampleChunk, Take
from tests.factories import (
    csrf_from,
    form_state,
    handout,
    login,
    make_course,
    make_user,
    new_session,
    post_form,
    post_json,
    save_manual,
)

DATA = Path(__file__).resolve().parent / "data"


def assert_same(actual, expected) -> None:
    """Equal results: numbers to 1e-9 relative, everything else exactly."""
    if isinstance(expected, dict):
        assert set(actual) == set(expected)
        for key in expected:
            assert_same(actual[key], expected[key])
    elif isinstance(expected, list | tuple):
        assert len(actual) == len(expected)
        for a, e in zip(actual, expected, strict=True):
            assert_same(a, e)
    elif isinstance(expected, float):
        assert actual == pytest.approx(expected, rel=1e-9, abs=1e-12)
    else:
        assert actual == expected


def count(model) -> int:
    with read_session() as db:
        return db.exec(select(func.count()).select_from(model)).one()


def test_practice_session_with_a_station_preset(student_client):
    session_id = new_session(student_client)
    with read_session() as db:
        session = db.get(LabSession, session_id)
    assert session.latitude_deg == 39.93 and session.earth_rate_deg_h == 15.04
    page = student_client.get(f"/lab/sessions/{session_id}")
    assert page.status_code == 200 and "Part A" in page.text
    assert str(session.sim_azimuth_deg) not in page.text  # the truth stays server-side


@pytest.mark.parametrize(
    ("fields", "message"),
    [
        ({"station": "custom"}, "Enter the station"),
        (
            {"station": "custom", "latitude_deg": "95", "earth_rate_deg_h": "15"},
            "between −90° and 90°",
        ),
        ({"station": "custom", "latitude_deg": "40", "earth_rate_deg_h": "-1"}, "positive number"),
    ],
)
def test_practice_session_validation(student_client, fields, message):
    response = post_form(
        student_client, "/lab/sessions", {"rotation": "ccw", **fields}, page="/lab"
    )
    assert response.status_code == 400 and message in response.text
    assert count(LabSession) == 0


def test_a_refused_practice_session_keeps_everything_typed_and_marks_every_field(
    student_client,
):
    typed = {
        "title": "Roof lab, group 7",
        "station": "custom",
        "latitude_deg": "91",
        "earth_rate_deg_h": "0",
        "rotation": "cw",
        "heading_start_deg": "12,5",
        "latitude_start_deg": "north",
        "latitude_step_deg": "90",
        "preset": "navigation-fog",
    }
    response = post_form(student_client, "/lab/sessions", typed, page="/lab")
    assert response.status_code == 400 and count(LabSession) == 0
    form = form_state(response.text, "new-session")
    assert form.values == typed
    assert form.refused == ["latitude_deg", "earth_rate_deg_h", "latitude_start_deg"]
    assert form.autofocus == "latitude_deg"
    assert form.errors == {
        "latitude_deg": "The latitude must be between −90° and 90°.",
        "earth_rate_deg_h": "The Earth rate must be a positive number of °/h.",
        "latitude_start_deg": "Type a number, e.g. 39.93.",
    }
    assert "3 fields need a change" in form.text


def test_typed_handout_tables_give_the_handout_results(student_client):
    session_id = new_session(student_client)
    assert (
        save_manual(
            student_client, session_id, "heading", handout("handout_horizontal.csv")
        ).status_code
        == 200
    )
    assert (
        save_manual(
            student_client, session_id, "latitude", handout("handout_vertical.csv")
        ).status_code
        == 200
    )
    results = student_client.get(f"/lab/sessions/{session_id}/results.json").json()
    assert results["heading"]["theta_deg"] == pytest.approx(-10.753, abs=5e-4)
    assert results["latitude"]["latitude_deg"] == pytest.approx(40.727, abs=5e-4)
    assert results["latitude"]["earth_rate_error_percent"] == pytest.approx(0.62, abs=5e-3)
    # the same numbers as the core on the same data (no recomputation elsewhere)
    expected = solve_heading(list(handout("handout_horizontal.csv").values()), heading_angles(4))
    assert_same(results["heading"], expected.to_json())
    page = student_client.get(f"/lab/sessions/{session_id}").text
    assert "-10.75°" in page and "40.73°" in page and "2.00 %" in page
    assert "tan θ = (ω4 − ω2) / (ω1 − ω3)" in page


def test_samples_are_stored_compactly_one_transaction(student_client):
    session_id = new_session(student_client)
    save_manual(student_client, session_id, "heading", handout("handout_horizontal.csv"))
    with read_session() as db:
        chunks = db.exec(select(SampleChunk)).all()
        takes = db.exec(select(Take)).all()
    assert len(takes) == 4 and len(chunks) == 4
    assert all(len(chunk.values) == 10 * 8 for chunk in chunks)
    assert unpack(chunks[0].values).tolist() == handout("handout_horizontal.csv")[1]


def test_units_are_converted(student_client):
    session_id = new_session(student_client)
    columns = {k: [v / 3600 for v in vals] for k, vals in handout("handout_horizontal.csv").items()}
    assert save_manual(student_client, session_id, "heading", columns, "deg/s").status_code == 200
    results = student_client.get(f"/lab/sessions/{session_id}/results.json").json()
    assert results["heading"]["position_means_deg_h"][0] == pytest.approx(10.706)


@pytest.mark.one_backend  # input refused before any write
@pytest.mark.parametrize(
    ("columns", "unit", "message"),
    [
        ({"1": [1.0] * 10, "2": [float("nan")] + [1.0] * 9}, "deg/h", "not a finite number"),
        ({"1": [1.0] * 10, "2": [float("inf")] * 10}, "deg/h", "not a finite number"),
        ({}, "deg/h", "at least one reading"),
        ({"1": [1.0] * 5}, "deg/h", "has 5 readings; at least 10"),
        ({"1": [10.7] * 10}, "deg/s", "check the unit"),
        ({"1": [1.0] * 10}, "furlongs/h", "Unknown unit"),
        ({"9": [1.0] * 10}, "deg/h", "no position 9"),
        ({"7": [1.0] * 10}, "deg/h", "Position 7 belongs to the symmetric order"),
    ],
)
def test_bad_typed_input_stores_nothing(student_client, columns, unit, message):
    session_id = new_session(student_client)
    response = save_manual(student_client, session_id, "heading", columns, unit)
    assert response.status_code == 400
    assert message in response.json()["detail"]
    assert count(Take) == 0 and count(SampleChunk) == 0


def test_non_numeric_typed_input_is_refused(student_client):
    session_id = new_session(student_client)
    for bad in (["abc"], [True], [None]):
        response = save_manual(student_client, session_id, "heading", {"1": bad * 10})
        assert response.status_code == 422
        assert isinstance(response.json()["detail"], list)
    assert count(Take) == 0


def test_csv_preview_stores_nothing_then_accept(student_client):
    session_id = new_session(student_client)
    text = (DATA / "handout_vertical.csv").read_text()
    page = f"/lab/sessions/{session_id}"
    preview = post_json(
        student_client,
        f"{page}/csv/preview",
        {"part": "latitude", "unit": "deg/h", "text": text},
        page,
    )
    assert preview.status_code == 200
    body = preview.json()
    assert [p["n"] for p in body["positions"]] == [10, 10, 10, 10]
    assert body["positions"][1]["angle_deg"] == 90.0
    assert count(Take) == 0
    saved = post_json(
        student_client, f"{page}/csv", {"part": "latitude", "unit": "deg/h", "text": text}, page
    )
    assert saved.status_code == 200 and saved.json()["saved"] == [1, 2, 3, 4]
    results = student_client.get(f"{page}/results.json").json()
    expected = solve_latitude(
        list(handout("handout_vertical.csv").values()),
        elevation_angles(4),
        true_latitude_deg=39.93,
        true_earth_rate_deg_h=15.04,
    )
    assert_same(results["latitude"], expected.to_json())


def test_csv_long_layout_keeps_angles_and_times(student_client):
    session_id = new_session(student_client)
    rows = ["position,angle_deg,time_s,value"]
    for position, angle in enumerate([0, 88, 181, 272], start=1):
        for i in range(12):
            value = 15.04 * np.cos(np.radians(angle - 39.93)) + 0.01 * (i % 3)
            rows.append(f"{position},{angle},{i * 0.5},{value}")
    page = f"/lab/sessions/{session_id}"
    response = post_json(
        student_client,
        f"{page}/csv",
        {"part": "latitude", "unit": "deg/h", "text": "\n".join(rows)},
        page,
    )
    assert response.status_code == 200
    with read_session() as db:
        angles = sorted(t.angle_deg for t in db.exec(select(Take)).all())
        chunk = db.exec(select(SampleChunk)).first()
    assert angles == [0, 88, 181, 272]
    assert unpack(chunk.times)[:3].tolist() == [0.0, 0.5, 1.0]
    latitude = student_client.get(f"{page}/results.json").json()["latitude"]["latitude_deg"]
    assert latitude == pytest.approx(39.93, abs=0.05)


def test_csv_long_layout_time_going_back_is_refused_and_a_coarse_clock_said(student_client):
    session_id = new_session(student_client)
    page = f"/lab/sessions/{session_id}"

    def table(time_of) -> str:
        rows = ["position,angle_deg,time_s,value"]
        for position, angle in enumerate([0, 90, 180, 270], start=1):
            rows += [
                f"{position},{angle},{time_of(position, i)},{10 + 0.01 * i}" for i in range(12)
            ]
        return "\n".join(rows)

    def send(path: str, text: str):
        body = {"part": "heading", "unit": "deg/h", "text": text}
        return post_json(student_client, f"{page}{path}", body, page)

    back = send("/csv", table(lambda position, i: 100 * position - i))
    assert back.status_code == 400 and "Line 3: the time goes back" in back.json()["detail"]
    preview = send("/csv/preview", table(lambda position, i: 100 * position + i // 3)).json()
    assert any("spread evenly over it" in note for note in preview["notes"])
    with read_session() as db:
        assert db.exec(select(Take)).first() is None


@pytest.mark.one_backend  # input refused before any write
@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("position_1,position_2\n1,abc\n", "'abc' is not a number"),
        ("position_1,position_2\n1,nan\n", "not a number"),
        ("", "no readings"),
        ("hello,world\n1,2\n", "reads 'hello | world'"),
        (
            "position_1,position_2,position_3,position_4,position_5\n" + "1,2,3,4,5\n" * 10,
            "at most 4 (8 in the symmetric order",
        ),
        ("position_1\n" + "1\n" * 3, "at least 10"),
        ("x" * 5_000_001, "larger than 5 MB"),
        ('position_1\n"' + "9" * 200_000 + '"\n', "cannot be read as CSV"),
    ],
)
def test_bad_csv_stores_nothing(student_client, text, message):
    session_id = new_session(student_client)
    page = f"/lab/sessions/{session_id}"
    for path in ("/csv/preview", "/csv"):
        response = post_json(
            student_client, page + path, {"part": "heading", "unit": "deg/h", "text": text}, page
        )
        if path == "/csv/preview" and message == "at least 10":
            assert response.status_code == 200  # the preview shows it; storing refuses
            continue
        assert response.status_code == 400, path
        assert message in response.json()["detail"]
    assert count(Take) == 0


def test_re_recording_keeps_history(student_client):
    session_id = new_session(student_client)
    save_manual(student_client, session_id, "heading", {"1": [1.0] * 10})
    save_manual(student_client, session_id, "heading", {"1": [2.0] * 12})
    with read_session() as db:
        takes = db.exec(select(Take).order_by(Take.id)).all()
    assert len(takes) == 2 and takes[0].superseded_at is not None and takes[1].n_samples == 12
    page = student_client.get(f"/lab/sessions/{session_id}").text
    assert "replaced" in page


def test_a_long_history_shows_its_latest_recordings_and_keeps_the_older_current_ones(
    student_client,
):
    """Part A saved once, then part B fourteen times: 60 recordings.  The page lists the
    50 most recent (all of part B) and says so; part A's result, from recordings older
    than those listed, is still there."""
    session_id = new_session(student_client)
    save_manual(student_client, session_id, "heading", handout("handout_horizontal.csv"))
    for _ in range(14):
        save_manual(student_client, session_id, "latitude", handout("handout_vertical.csv"))
    page = student_client.get(f"/lab/sessions/{session_id}").text
    history = page.split('id="take-history"', 1)[1].split("</section>", 1)[0]
    assert history.count("<tr") == 1 + 50  # the head row and the 50 most recent
    assert "The 50 most recent of 60 recordings are shown" in history
    # part A's four are older than all of those listed
    assert history.count("<td>A</td>") == 0 and history.count("<td>B</td>") == 50
    assert "-10.75°" in page  # part A's θ, from its current (older) takes
    zh = student_client.get(f"/lab/sessions/{session_id}", headers={"Accept-Language": "zh-CN"})
    assert "仅显示 60 次记录中最近的 50 次" in zh.text


def test_submit_freezes_an_attempt_and_edits_start_a_new_one(student_client):
    session_id = new_session(student_client)
    page = f"/lab/sessions/{session_id}"
    response = post_form(student_client, f"{page}/submit", page=page)
    assert "no result to submit" in student_client.get(page).text
    save_manual(student_client, session_id, "heading", handout("handout_horizontal.csv"))
    post_form(student_client, f"{page}/submit", page=page)
    with read_session() as db:
        assert db.get(LabSession, session_id).status == "submitted"
        first = db.exec(select(Attempt)).one()
    frozen = json.loads(first.results_json)
    assert frozen["heading"]["theta_deg"] == pytest.approx(-10.753, abs=5e-4)
    assert frozen["latitude"] is None
    save_manual(student_client, session_id, "heading", {"1": [11.0] * 10})
    with read_session() as db:
        assert db.get(LabSession, session_id).status == "in_progress"
    response = post_form(student_client, f"{page}/submit", page=page)
    assert response.status_code == 303
    with read_session() as db:
        attempts = db.exec(select(Attempt).order_by(Attempt.number)).all()
    assert [a.number for a in attempts] == [1, 2]
    assert json.loads(attempts[0].results_json) == frozen  # nothing overwritten


def test_exports(student_client):
    session_id = new_session(student_client)
    save_manual(student_client, session_id, "heading", handout("handout_horizontal.csv"))
    save_manual(student_client, session_id, "latitude", handout("handout_vertical.csv"))
    exported = student_client.get(f"/lab/sessions/{session_id}/export.csv")
    assert exported.status_code == 200
    # named after the session and the student (the owner's username), with the date
    disposition = exported.headers["content-disposition"]
    assert re.search(r"filename\*=UTF-8''[^;]*_student1_\d{8}\.csv$", disposition), disposition
    assert re.search(r'filename="[A-Za-z0-9_.-]+_student1_\d{8}\.csv"', disposition)
    text = exported.content.decode("utf-8-sig")
    assert text.startswith("# GyroLab")
    readings = parse_readings_csv(text, part="latitude")
    assert [len(p) for p in readings.positions] == [10, 10, 10, 10]
    document = student_client.get(f"/lab/sessions/{session_id}/export.json").json()
    assert document["metadata"]["station"]["latitude_deg"] == 39.93
    assert document["metadata"]["software"].startswith("GyroLab")
    assert len(document["positions"]) == 8 and document["positions"][0]["source"] == "manual"
    assert document["results"]["heading"]["theta_deg"] == pytest.approx(-10.753, abs=5e-4)
    assert "sim_azimuth" not in json.dumps(document) and "seed" not in json.dumps(document)


def test_other_students_cannot_see_or_touch_a_session(client, app):
    from fastapi.testclient import TestClient

    make_user("owner", Role.student)
    make_user("other", Role.student)
    with TestClient(app, follow_redirects=False) as owner:
        login(owner, "owner")
        session_id = new_session(owner)
        save_manual(owner, session_id, "heading", handout("handout_horizontal.csv"))
    login(client, "other")
    base = f"/lab/sessions/{session_id}"
    for path in ("", "/results.json", "/export.csv", "/export.json"):
        assert client.get(base + path).status_code == 404
    token = csrf_from(client, "/lab")
    for path, body in (
        ("/manual", {"part": "heading", "columns": {"1": [1.0] * 10}}),
        ("/csv", {"part": "heading", "text": "position_1\n1\n"}),
        ("/csv/preview", {"part": "heading", "text": "position_1\n1\n"}),
        ("/turn", {"part": "heading", "position": 2}),
    ):
        response = client.post(base + path, json=body, headers={"X-CSRF-Token": token})
        assert response.status_code == 404, path
    assert client.post(base + "/submit", data={"csrf_token": token}).status_code == 404
    assert count(Take) == 4


def test_json_endpoints_need_csrf(student_client):
    session_id = new_session(student_client)
    response = student_client.post(
        f"/lab/sessions/{session_id}/manual", json={"part": "heading", "columns": {"1": [1.0] * 10}}
    )
    assert response.status_code == 403 and count(Take) == 0


@pytest.fixture
def assignment_world(teacher):
    student = make_user("s1", Role.student)
    outsider = make_user("s2", Role.student)
    course_id = make_course(teacher, "Nav lab", (student,))
    with write_session() as db:
        assignment = Assignment(
            course_id=course_id,
            title="Find north",
            latitude_deg=34.26,
            earth_rate_deg_h=15.041,
            allowed_methods="manual",
            simulator_preset="tactical-fog",
            min_readings=12,
        )
        db.add(assignment)
        db.flush()
        return {
            "assignment": assignment.id,
            "course": course_id,
            "student": student,
            "outsider": outsider,
        }


def test_teacher_creates_an_assignment(client, teacher):
    course_id = make_course(teacher, "Nav lab")
    login(client, "teacher1")
    page = f"/courses/{course_id}"
    response = post_form(
        client,
        f"{page}/assignments",
        {
            "title": "寻北实验",
            "instructions": "Use 12 readings.",
            "latitude_deg": "39.93",
            "earth_rate_deg_h": "15.04",
            "methods": ["manual", "simulator"],
            "simulator_preset": "teaching-fog",
            "min_readings": "12",
            "due_at": "2030-01-31T18:00",
        },
        page=page,
    )
    assert response.status_code == 303
    with read_session() as db:
        assignment = db.exec(select(Assignment)).one()
    assert assignment.methods == ["manual", "simulator"] and assignment.min_readings == 12
    assert assignment.due_at.year == 2030
    bad = post_form(
        client,
        f"{page}/assignments",
        {"title": "x", "latitude_deg": "north", "methods": ["manual"]},
        page=page,
    )
    assert bad.status_code == 400 and "Type a number from -90 to 90" in bad.text
    kept = form_state(bad.text, "new-assignment")
    assert kept.values["latitude_deg"] == "north" and kept.refused == ["latitude_deg"]
    bad = post_form(client, f"{page}/assignments", {"title": "x", "latitude_deg": "40"}, page=page)
    assert bad.status_code == 400 and "at least one way" in bad.text


def test_student_starts_an_assignment_with_its_settings(client, assignment_world):
    login(client, "s1")
    assert "Find north" in client.get("/lab").text
    session_id = new_session(client, assignment_id=str(assignment_world["assignment"]))
    with read_session() as db:
        session = db.get(LabSession, session_id)
    assert session.latitude_deg == 34.26 and session.min_readings == 12
    assert session.simulator_preset == "tactical-fog" and session.title == "Find north"
    page = f"/lab/sessions/{session_id}"
    assert save_manual(client, session_id, "heading", {"1": [1.0] * 10}).status_code == 400
    denied = post_json(client, f"{page}/csv", {"part": "heading", "text": "position_1\n1\n"}, page)
    assert denied.status_code == 403  # this assignment allows typing only


def test_outsider_cannot_start_someone_elses_assignment(client, assignment_world):
    login(client, "s2")
    assert "Find north" not in client.get("/lab").text
    response = post_form(
        client, "/lab/sessions", {"assignment_id": str(assignment_world["assignment"])}, page="/lab"
    )
    assert response.status_code == 404 and count(LabSession) == 0


def test_data_quality_flags_are_shown(student_client):
    session_id = new_session(student_client)
    rng = np.random.default_rng(4)
    columns = {str(k): (rng.normal(5.0 * k, 0.05, 12)).tolist() for k in (1, 2, 3, 4)}
    columns["2"] = (rng.normal(3.0, 0.05, 12)).tolist()
    columns["2"][5] = 4.0  # a spike
    columns["4"] = (rng.normal(-2.0, 3.0, 12)).tolist()  # a noisy position
    assert save_manual(student_client, session_id, "heading", columns).status_code == 200
    page = student_client.get(f"/lab/sessions/{session_id}")
    assert page.status_code == 200
    assert "Position 2 has 1 spike(s)" in page.text
    assert "Position 4 is" in page.text and "noisier than the others" in page.text


def test_csv_with_old_mac_line_ends_is_read(student_client):
    """Files saved with bare CR line ends (old Mac Excel) are lines, not one bad field."""
    session_id = new_session(student_client)
    page = f"/lab/sessions/{session_id}"
    text = "position_1,position_2\r" + "10.5,2.7\r" * 10
    response = post_json(
        student_client, page + "/csv", {"part": "heading", "unit": "deg/h", "text": text}, page
    )
    assert response.status_code == 200
    assert count(Take) == 2


def test_the_symmetric_order_adds_positions_five_to_eight(student_client):
    """Off: positions 5–8 do not exist (turning there is refused, readings too).  On: the
    page has eight positions, 5–8 at the dial angles of 4–1, and the fit uses all eight;
    switching back is refused once the return pass holds readings."""
    session_id = new_session(student_client)
    page = f"/lab/sessions/{session_id}"
    reply = post_json(student_client, f"{page}/turn", {"part": "heading", "position": 5}, page)
    assert reply.status_code == 400 and "symmetric" in reply.json()["detail"]
    rng = np.random.default_rng(8)
    means = [10.71, 2.79, -8.95, -0.94]
    columns = {str(k): list(rng.normal(means[k - 1], 0.05, 10)) for k in range(1, 5)}
    columns["5"] = list(rng.normal(means[3], 0.05, 10))
    reply = post_json(
        student_client, f"{page}/manual", {"part": "heading", "columns": columns}, page
    )
    assert reply.status_code == 400 and "symmetric order" in reply.json()["detail"]
    assert "1-2-3-4-4-3-2-1" in student_client.get(page).text
    reply = post_form(student_client, f"{page}/order", {"symmetric": "on"}, page=page)
    assert reply.status_code == 303
    html = student_client.get(page).text
    assert 'data-position="8"' in html and "Symmetric order on" in html
    for k in range(5, 9):  # the return pass: 4, 3, 2, 1 again
        columns[str(k)] = list(rng.normal(means[8 - k], 0.05, 10))
    reply = post_json(
        student_client, f"{page}/manual", {"part": "heading", "columns": columns}, page
    )
    assert reply.status_code == 200, reply.text
    results = student_client.get(f"{page}/results.json").json()["heading"]
    assert results["n_positions"] == 8
    found = results["position_means_deg_h"]
    assert found[4:] == pytest.approx(found[3::-1], abs=0.1)  # 5–8 at the angles of 4–1
    assert results["theta_deg"] == pytest.approx(-10.75, abs=0.1)
    reply = post_form(student_client, f"{page}/order", {"symmetric": "off"}, page=page)
    assert reply.status_code == 303
    html = student_client.get(page).text
    assert "Positions 5–8 already hold readings" in html and 'data-position="8"' in html
    reply = post_form(student_client, f"{page}/order", {"symmetric": "sideways"}, page=page)
    assert reply.status_code == 303
    assert "Choose the recording order" in student_client.get(page).text


def test_readings_saved_in_the_wrong_unit_are_named(student_client):
    """The handout's readings typed in °/s but saved as °/h: the heading is the same (a
    ratio), Earth's rate 3600× small.  Each part's results say which unit they look like,
    and name no expected value."""
    words = "about 3600: were they recorded in °/s and saved as °/h?"
    session_id = new_session(student_client)
    for part, name in (("heading", "handout_horizontal.csv"), ("latitude", "handout_vertical.csv")):
        columns = {k: [v / 3600 for v in vals] for k, vals in handout(name).items()}
        assert save_manual(student_client, session_id, part, columns, "deg/h").status_code == 200
    results = student_client.get(f"/lab/sessions/{session_id}/results.json").json()
    assert results["heading"]["theta_deg"] == pytest.approx(-10.753, abs=5e-4)  # a ratio
    page = student_client.get(f"/lab/sessions/{session_id}").text
    assert page.count(words) == 2  # once in each part

    right = new_session(student_client)  # the same readings saved as °/s: no such words
    for part, name in (("heading", "handout_horizontal.csv"), ("latitude", "handout_vertical.csv")):
        columns = {k: [v / 3600 for v in vals] for k, vals in handout(name).items()}
        assert save_manual(student_client, right, part, columns, "deg/s").status_code == 200
    assert "were they recorded in" not in student_client.get(f"/lab/sessions/{right}").text
