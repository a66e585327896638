"""Issue 34 item 7: the class table names every lab partner and carries the review
(feedback, position comments, each rubric criterion's points); the data zip has a folder
for each partner.  In the teacher's words on the page, in machine names on the API."""

from __future__ import annotations

import csv
import io
import json
import zipfile

from app.db import write_session
from app.models import Assignment
from tests.factories import API, browser, do_lab, review, start, submit, token_for
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
    # the class as a whole: the board (one point per session, named), the accuracy against
    # the planner, and the plan itself
    board = json.loads(archive.read("class-board.json"))
    assert board["names_shown"] is True and len(board["groups"]) >= 1
    assert board["earth_rate"]["groups"] == len(board["groups"])
    assert "heading" in json.loads(archive.read("class-accuracy.json"))
    plan = json.loads(archive.read("accuracy-plan.json"))
    assert plan["source"] == "preset" and len(plan["points"]) == 22
