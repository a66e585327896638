"""Issue 34 item 7: the class table names every lab partner and carries the review
(feedback, position comments, each rubric criterion's points); the data zip has a folder
for each partner.  In the teacher's words on the page, in machine names on the API."""

from __future__ import annotations

import csv
import io
import json
import zipfile

import openpyxl
import pytest

from app.accounts.service import enroll
from app.db import write_session
from app.models import Assignment, Course, User
from app.web.workbooks import XLSX_CELL_LIMIT, XLSX_MEDIA_TYPE, xlsx_table, xlsx_text
from tests.factories import (
    API,
    browser,
    csrf_from,
    do_lab,
    make_user,
    review,
    start,
    submit,
    token_for,
)
from tests.test_partners import allow_groups, code_of, join

RUBRIC = [{"name": "Method", "points": 40}, {"name": "Results", "points": 60}]


def graded_pair(world) -> int:
    """s1 and s2 share a session; it is submitted and released with a rubric and comments."""
    allow_groups(world)
    with write_session() as db:
        assignment = db.get(Assignment, world["assignment"])
        assignment.rubric = json.dumps(RUBRIC)
        db.add(assignment)
    s1 = browser(world, "s1")
    session_id = start(s1, world)
    assert join(browser(world, "s2"), code_of(session_id)).status_code == 303
    do_lab(s1, session_id)
    submit(s1, session_id)
    teacher = browser(world, "teacher1")
    response = review(
        teacher,
        session_id,
        **{"rubric-0": "35", "rubric-1": "50,5", "comment-latitude-2": "Let the table settle."},
        feedback="=HYPERLINK(good teamwork)",
        action="release",
    )
    assert response.status_code == 303, response.text[:400]
    return session_id


def rows_of(text: str) -> list[dict]:
    return list(csv.DictReader(io.StringIO(text.lstrip("\ufeff"))))


def test_the_class_table_names_partners_and_holds_the_review(world):
    graded_pair(world)
    teacher = browser(world, "teacher1")
    base = f"/courses/{world['course']}/assignments/{world['assignment']}"
    page = {row["Username"]: row for row in rows_of(teacher.get(f"{base}/export.csv").text)}
    assert page["s1"]["Lab partners"] == "s2" and page["s2"]["Lab partners"] == "s1"
    assert page["s3"]["Lab partners"] == "" and page["s3"]["Feedback"] == ""
    for username in ("s1", "s2"):  # one grade, one review, for both partners
        row = page[username]
        assert row["Feedback"] == "'=HYPERLINK(good teamwork)"  # safe in a spreadsheet
        assert row["Comments on positions"] == "B2: Let the table settle."
        assert row["Rubric 1: Method (of 40)"] == "35"
        assert row["Rubric 2: Results (of 60)"] == "50.5"
        assert row["Points"] == "85.5000"

    api = teacher.get(
        f"{API}/assignments/{world['assignment']}/export.csv",
        headers=token_for(teacher, "teacher1"),
    )
    machine = {row["username"]: row for row in rows_of(api.text)}
    assert machine["s2"]["partners"] == "s1"
    assert machine["s1"]["position_comments"] == "latitude-2: Let the table settle."
    assert machine["s1"]["rubric_1:Method"] == "35" and machine["s1"]["rubric_2:Results"] == "50.5"

    archive = zipfile.ZipFile(io.BytesIO(teacher.get(f"{base}/export.zip").content))
    names = set(archive.namelist())
    assert {"s1/attempt-1.csv", "s2/attempt-1.csv", "s2/attempt-1.json"} <= names
    zipped = {row["Username"]: row for row in rows_of(archive.read("class.csv").decode())}
    assert zipped["s2"]["Lab partners"] == "s1"
    title, cells = workbook_rows(archive.read("class.xlsx"))  # the same table for Excel
    booked = {row[0]: dict(zip(cells[0], row, strict=True)) for row in cells[1:]}
    assert title == "Class table" and list(cells[0]) == list(zipped["s1"])
    assert booked["s2"]["Lab partners"] == "s1" and booked["s1"]["Points"] == 85.5
    # the class as a whole: the board (one point per session, named), the accuracy against
    # the planner, and the plan itself
    board = json.loads(archive.read("class-board.json"))
    assert board["names_shown"] is True and len(board["groups"]) >= 1
    assert board["earth_rate"]["groups"] == len(board["groups"])
    assert "heading" in json.loads(archive.read("class-accuracy.json"))
    plan = json.loads(archive.read("accuracy-plan.json"))
    assert plan["source"] == "preset" and len(plan["points"]) == 22


def workbook_rows(content: bytes) -> tuple[str, list[tuple]]:
    """The sheet's title and its cells (openpyxl: an independent reader), refusing formulas."""
    sheet = openpyxl.load_workbook(io.BytesIO(content)).worksheets[0]
    for row in sheet.iter_rows():
        for cell in row:
            assert cell.data_type != "f", f"{cell.coordinate} is a formula: {cell.value!r}"
    return sheet.title, [tuple(row) for row in sheet.iter_rows(values_only=True)]


def test_the_class_table_as_a_workbook_keeps_student_numbers_as_text(world):
    """Excel opens the CSV's "202301010101" as 2.02301E+11 and "007" as 7; the workbook
    holds them as text, and the results, points and rubric scores as numbers."""
    graded_pair(world)
    long_number = make_user("202301010101", name='=HYPERLINK("http://x","y")')
    leading_zeros = make_user("007", name="@SUM(1+1)")
    with write_session() as db:
        course = db.get(Course, world["course"])
        enroll(db, course, db.get(User, long_number.id))
        enroll(db, course, db.get(User, leading_zeros.id))
    teacher = browser(world, "teacher1")
    base = f"/courses/{world['course']}/assignments/{world['assignment']}"
    response = teacher.get(f"{base}/export.xlsx")
    assert response.status_code == 200
    assert response.headers["content-type"] == XLSX_MEDIA_TYPE
    assert ".xlsx" in response.headers["content-disposition"]
    title, cells = workbook_rows(response.content)
    csv_rows = list(
        csv.reader(io.StringIO(teacher.get(f"{base}/export.csv").text.lstrip("\ufeff")))
    )
    assert title == "Class table" and list(cells[0]) == csv_rows[0]  # the CSV's columns
    header = list(cells[0])
    rows = {row[0]: dict(zip(header, row, strict=True)) for row in cells[1:]}
    assert set(rows) == {"s1", "s2", "s3", "202301010101", "007"}
    assert rows["202301010101"]["Name"] == '=HYPERLINK("http://x","y")'  # text, as typed
    assert rows["007"]["Name"] == "@SUM(1+1)"
    s1 = rows["s1"]
    assert s1["Feedback"] == "=HYPERLINK(good teamwork)"  # no apostrophe needed: it is text
    assert s1["Rubric 1: Method (of 40)"] == 35 and s1["Rubric 2: Results (of 60)"] == 50.5
    assert s1["Points"] == 85.5 and s1["Lab partners"] == "s2"
    by_name = {row[0]: dict(zip(csv_rows[0], row, strict=True)) for row in csv_rows[1:]}
    for column in (
        "Azimuth of position 1 (°)",
        "Attempts",
    ):  # the same numbers as the CSV, as numbers
        assert column in header, header
        assert isinstance(s1[column], float | int)
        assert s1[column] == pytest.approx(float(by_name["s1"][column]))
    assert (
        rows["s3"]["Azimuth of position 1 (°)"] is None
    )  # nothing measured: an empty cell, not "" or 0

    teacher.post("/lang", data={"lang": "zh", "csrf_token": csrf_from(teacher, base)})
    title, cells = workbook_rows(teacher.get(f"{base}/export.xlsx").content)
    zh_csv = next(csv.reader(io.StringIO(teacher.get(f"{base}/export.csv").text.lstrip("\ufeff"))))
    assert title == "全班成绩表" and list(cells[0]) == zh_csv

    api = teacher.get(
        f"{API}/assignments/{world['assignment']}/export.xlsx",
        headers=token_for(teacher, "teacher1"),
    )
    assert api.status_code == 200 and api.headers["content-type"] == XLSX_MEDIA_TYPE
    title, cells = workbook_rows(api.content)
    machine = {row[0]: dict(zip(cells[0], row, strict=True)) for row in cells[1:]}
    assert title == "class" and cells[0][:2] == ("username", "display_name")
    assert machine["s1"]["rubric_1:Method"] == 35 and machine["202301010101"]["status"]


def test_workbook_text_is_what_excel_can_hold():
    """Control characters become spaces (a tab and a line break stay), a lone surrogate the
    replacement character, and a cell longer than Excel's 32,767 characters is cut visibly."""
    assert xlsx_text("a\x00b\x1fc\td\ne\x7f") == "a b c\td\ne "
    assert xlsx_text("x\ud800y") == "x\ufffdy"
    cut = xlsx_text("z" * 40_000)
    assert len(cut) == XLSX_CELL_LIMIT and cut.endswith("…")
    content = xlsx_table([["name", "n"], ["\x01=1+1", "1e400"], ["z" * 40_000, ""]], [1], "s")
    _title, cells = workbook_rows(content)
    assert cells[1] == (" =1+1", "1e400")  # Excel has no ∞: the text as it was
    assert len(cells[2][0]) == XLSX_CELL_LIMIT and cells[2][1] is None
