"""Teacher review: truth per student, auto-checks, states and transitions, exports, access."""

from __future__ import annotations

import csv
import io
import json
import random
import re
import zipfile
from datetime import timedelta

import pytest
from sqlmodel import select

from app.db import read_session, write_session
from app.lab.truth import Truth, auto_check, draw_truth, heading_error
from app.models import Assignment, Attempt, LabSession, Role, utcnow
from tests.factories import (
    HEADING,
    browser,
    csrf_from,
    do_lab,
    form_state,
    make_user,
    post_form,
    review,
    save_manual,
    set_assignment,
    start,
    submit,
)


def grade_cells(page: str) -> list[str]:
    """The grades a student's dashboard shows, one per assignment (exact, not a substring
    test: a random CSRF token on the page may contain "A-")."""
    return [cell.strip() for cell in re.findall(r'<td class="grade"[^>]*>([^<]*)</td>', page)]


def session_of(session_id) -> LabSession:
    with read_session() as db:
        return db.get(LabSession, session_id)


def test_heading_error_wraps_around_north():
    assert heading_error(359.5, 0.5) == pytest.approx(-1.0)
    assert heading_error(0.5, 359.5) == pytest.approx(1.0)
    assert heading_error(180.0, 0.0) == pytest.approx(180.0)
    assert heading_error(None, 3.0) is None
    truth = Truth(0.5, 40.0, 15.041, None, "simulator")
    assignment = Assignment(course_id=1, title="t", latitude_deg=40.0, tolerance_heading_deg=2.0)
    results = {
        "heading": {"azimuth_deg": 359.2},
        "latitude": {"latitude_deg": 41.0, "earth_rate_deg_h": 15.1},
    }
    check = auto_check(results, truth, assignment)
    assert [c.passed for c in check.checks] == [True, True, True]
    assert check.checks[0].error == pytest.approx(-1.3)
    assert check.checks[1].error == pytest.approx(2.5)
    results["heading"]["azimuth_deg"] = 357.0
    assert auto_check(results, truth, assignment).passed is False
    assert auto_check({}, truth, assignment).passed is None  # nothing to check


def test_truth_is_drawn_per_student_within_the_ranges():
    assignment = Assignment(
        course_id=1,
        title="t",
        latitude_deg=40.0,
        azimuth_min_deg=350.0,
        azimuth_max_deg=20.0,
        turn_on_bias_max_deg_h=2.0,
        indexing_sigma_arcsec=30.0,
    )
    rng = random.Random(1)
    drawn = []
    for _ in range(200):
        session = LabSession(owner_id=1, title="x", latitude_deg=40.0)
        draw_truth(assignment, session, rng)
        drawn.append(session)
    azimuths = [s.sim_azimuth_deg for s in drawn]
    assert all(a >= 350 or a <= 20 for a in azimuths)  # the range wraps through north
    assert len(set(azimuths)) == 200
    assert all(abs(s.sim_turn_on_bias_deg_h) <= 2.0 for s in drawn)
    assert all(s.sim_indexing_sigma_arcsec == 30.0 for s in drawn)


def test_full_cycle_submit_return_resubmit_grade_release(world):
    teacher = browser(world, "teacher1")
    student = browser(world, "s1")
    session_id = start(student, world)
    assert start(student, world) == session_id  # one session per student and assignment
    do_lab(student, session_id)
    submit(student, session_id)
    assert session_of(session_id).status == "submitted"
    # while waiting for review the student can neither edit nor submit again
    assert save_manual(student, session_id, "heading", {"1": [1.0] * 10}).status_code == 409
    submit(student, session_id)
    with read_session() as db:
        assert len(db.exec(select(Attempt)).all()) == 1
    # the teacher comments and returns it
    response = review(
        teacher,
        session_id,
        feedback="Position 3 looks noisy.",
        **{"comment-heading-3": "Wait until the table settles."},
        action="return",
    )
    assert response.status_code == 303
    assert session_of(session_id).status == "returned"
    page = student.get(f"/lab/sessions/{session_id}").text
    assert "Position 3 looks noisy." in page and "Wait until the table settles." in page
    assert "returned" in student.get("/").text
    # the student revises one position: the feedback stays on the page during the fix
    assert save_manual(student, session_id, "heading", HEADING).status_code == 200
    assert session_of(session_id).status == "in_progress"
    page = student.get(f"/lab/sessions/{session_id}").text
    assert "Position 3 looks noisy." in page and "Wait until the table settles." in page
    assert 'id="revising-notice"' in page
    submit(student, session_id)
    with read_session() as db:
        assert [a.number for a in db.exec(select(Attempt).order_by(Attempt.number))] == [1, 2]
    # after the next submission attempt 1's review is listed with attempt 1 only
    page = student.get(f"/lab/sessions/{session_id}").text
    assert (
        'id="overall-feedback"' not in page
        and 'class="flash flash-info position-comment"' not in page
    )
    assert 'data-attempt="1"' in page and "Position 3 looks noisy." in page
    # the teacher's next review starts empty: attempt 1's comment is not carried over
    form = teacher.get(f"/review/sessions/{session_id}").text
    assert 'value="Wait until the table settles."' not in form
    assert "Review of attempt 1" in form
    # draft grades are not shown; released ones are
    review(teacher, session_id, feedback="Good.", points="87", letter="A-", action="save")
    assert grade_cells(student.get("/").text) == ["—"]
    assert (
        review(
            teacher, session_id, feedback="Good.", points="87", letter="A-", action="release"
        ).status_code
        == 303
    )
    assert session_of(session_id).status == "graded"
    dashboard = student.get("/").text
    assert grade_cells(dashboard) == ["87 / 100 (A-)"] and "Good." in dashboard
    # attempt 1's position comment is not released again with attempt 2's grade
    page = student.get(f"/lab/sessions/{session_id}").text
    assert page.count("Wait until the table settles.") == 1  # in attempt 1's entry only
    assert save_manual(student, session_id, "heading", HEADING).status_code == 409  # graded
    submission = teacher.get(f"/review/sessions/{session_id}").text
    assert "Attempt 2" in submission and "Attempt 1" in submission


def test_release_needs_a_grade_and_a_submission(world):
    teacher = browser(world, "teacher1")
    student = browser(world, "s1")
    session_id = start(student, world)
    review(teacher, session_id, points="80", action="release")
    assert session_of(session_id).status == "in_progress"
    do_lab(student, session_id)
    submit(student, session_id)
    answer = review(teacher, session_id, points="", feedback="Nearly there.", action="release")
    assert session_of(session_id).status == "submitted"
    assert "Enter the points" in answer.text and "Nearly there.</textarea>" in answer.text
    assert 'id="points" inputmode="decimal" value="" aria-invalid="true"' in answer.text


def test_late_submission_is_accepted_and_flagged(world):
    set_assignment(world, due_at=utcnow() - timedelta(hours=1), late_policy="accept")
    student = browser(world, "s1")
    session_id = start(student, world)
    do_lab(student, session_id)
    submit(student, session_id)
    with read_session() as db:
        assert db.exec(select(Attempt)).one().late
    teacher = browser(world, "teacher1")
    page = teacher.get(f"/courses/{world['course']}/assignments/{world['assignment']}").text
    assert "late" in page


def test_late_submission_is_refused_when_the_policy_says_so(world):
    set_assignment(world, due_at=utcnow() - timedelta(hours=1), late_policy="refuse")
    student = browser(world, "s1")
    session_id = start(student, world)
    do_lab(student, session_id)
    submit(student, session_id)
    assert "submissions are closed" in student.get(f"/lab/sessions/{session_id}").text
    assert session_of(session_id).status == "in_progress"


def test_maximum_attempts(world):
    set_assignment(world, max_attempts=1)
    teacher = browser(world, "teacher1")
    student = browser(world, "s1")
    session_id = start(student, world)
    do_lab(student, session_id)
    submit(student, session_id)
    review(teacher, session_id, action="return")
    save_manual(student, session_id, "heading", HEADING)
    submit(student, session_id)
    assert "attempts are used" in student.get(f"/lab/sessions/{session_id}").text


@pytest.mark.one_backend  # the reveal rule, not the database
@pytest.mark.parametrize(
    ("policy", "after_submit", "after_grade"),
    [
        ("never", False, False),
        ("after_submission", True, True),
        ("after_grading", False, True),
    ],
)
def test_truth_is_revealed_only_when_the_rule_allows(world, policy, after_submit, after_grade):
    set_assignment(world, reveal_truth=policy)
    teacher = browser(world, "teacher1")
    student = browser(world, "s1")
    session_id = start(student, world)
    # a truth no number of the handout's results can hold by chance (a drawn one, "0.10",
    # was found inside "10.107…" once); the readings typed are the handout's, not simulated
    with write_session() as db:
        db.get(LabSession, session_id).sim_azimuth_deg = 277.3141
    secret = "277.314"
    page = student.get(f"/lab/sessions/{session_id}").text
    assert "True values and auto-check" not in page
    do_lab(student, session_id)
    submit(student, session_id)
    page = student.get(f"/lab/sessions/{session_id}").text
    assert ("True values and auto-check" in page) is after_submit
    review(teacher, session_id, points="80", action="release")
    page = student.get(f"/lab/sessions/{session_id}").text
    assert ("True values and auto-check" in page) is after_grade
    # JSON and exports never carry the simulator's secrets
    for path in ("/results.json", "/export.json", "/export.csv"):
        body = student.get(f"/lab/sessions/{session_id}{path}").text
        assert "sim_azimuth" not in body and "sim_seed" not in body
    assert secret not in student.get(f"/lab/sessions/{session_id}/results.json").text


def test_dashboard_rows_counts_checks_and_identical_data(world):
    teacher = browser(world, "teacher1")
    for username in ("s1", "s2"):
        student = browser(world, username)
        session_id = start(student, world)
        do_lab(student, session_id)  # both typed the same handout tables
        submit(student, session_id)
    page = teacher.get(f"/courses/{world['course']}/assignments/{world['assignment']}")
    assert page.status_code == 200
    text = page.text
    assert "same data as s2" in text and "same data as s1" in text
    assert 'data-status="submitted"' in text
    assert ">submitted <strong>2</strong>" in text and ">not started <strong>1</strong>" in text
    assert "pass" in text  # 10.753° against the bench's 10.8°: within 2°
    filtered = teacher.get(
        f"/courses/{world['course']}/assignments/{world['assignment']}?status=not_started"
    ).text
    table = filtered[filtered.index('id="class-table"') : filtered.index("</table>")]
    assert "学生3" in table and "学生1" not in table  # (the charts' data lists everyone)


def test_csv_export_opens_in_excel_with_chinese_names(world):
    teacher = browser(world, "teacher1")
    student = browser(world, "s1")
    session_id = start(student, world)
    do_lab(student, session_id)
    submit(student, session_id)
    base = f"/courses/{world['course']}/assignments/{world['assignment']}"
    response = teacher.get(f"{base}/export.csv")
    assert response.content.startswith("\ufeff".encode())
    # named after the course and assignment (UTF-8 filename* with an ASCII fallback)
    disposition = response.headers["content-disposition"]
    assert 'filename="Nav-lab_Find-north.csv"' in disposition
    assert "filename*=UTF-8''Nav-lab-%E6%83%AF%E5%AF%BC_Find-north.csv" in disposition
    # the page's download speaks the teacher's language; the API's keeps machine names
    rows = list(csv.DictReader(io.StringIO(response.content.decode("utf-8-sig"))))
    assert [r["Name"] for r in rows] == ["学生1", "学生2", "学生3"]
    first = rows[0]
    assert first["Status"] == "submitted" and first["Late"] == "no"
    assert float(first["Heading error (°)"]) == pytest.approx(10.753 - 10.8, abs=1e-3)
    assert float(first["Latitude error (%)"]) == pytest.approx(2.00, abs=5e-3)
    assert first["Auto-check"] == "pass"
    assert rows[1]["Status"] == "not started" and rows[1]["Azimuth of position 1 (°)"] == ""
    teacher.post("/lang", data={"lang": "zh", "csrf_token": csrf_from(teacher, base)})
    chinese = teacher.get(f"{base}/export.csv").content.decode("utf-8-sig")
    assert chinese.startswith("用户名,姓名,实验搭档,状态") and ",已提交," in chinese
    archive = zipfile.ZipFile(io.BytesIO(teacher.get(f"{base}/export.zip").content))
    names = set(archive.namelist())
    assert {"class.csv", "s1/attempt-1.csv", "s1/attempt-1.json"} <= names
    document = json.loads(archive.read("s1/attempt-1.json"))
    assert document["attempts"][0]["results"]["heading"]["theta_deg"] == pytest.approx(
        -10.753, abs=1e-3
    )
    assert document["results"] == document["attempts"][0]["results"]
    assert len(document["positions"]) == 8 and document["metadata"]["attempt"]["number"] == 1


def test_settings_form_updates_the_rules(world):
    teacher = browser(world, "teacher1")
    page = f"/courses/{world['course']}/assignments/{world['assignment']}"
    response = post_form(
        teacher,
        f"{page}/settings",
        {
            "title": "Find north v2",
            "latitude_deg": "39.93",
            "earth_rate_deg_h": "15.04",
            "methods": ["simulator"],
            "simulator_preset": "tactical-fog",
            "min_readings": "20",
            "azimuth_min_deg": "0",
            "azimuth_max_deg": "90",
            "tolerance_heading_deg": "1.5",
            "tolerance_latitude_pct": "3",
            "tolerance_earth_rate_pct": "3",
            "max_attempts": "2",
            "late_policy": "refuse",
            "reveal_truth": "never",
            "turn_on_bias_max_deg_h": "1",
        },
        page=page,
    )
    assert response.status_code == 303
    with read_session() as db:
        assignment = db.get(Assignment, world["assignment"])
    assert assignment.title == "Find north v2" and assignment.methods == ["simulator"]
    assert assignment.tolerance_heading_deg == 1.5 and assignment.late_policy == "refuse"
    assert assignment.turn_on_bias_max_deg_h == 1.0 and assignment.true_heading_deg is None
    bad = post_form(
        teacher,
        f"{page}/settings",
        {"title": "x", "latitude_deg": "39", "methods": ["manual"], "tolerance_heading_deg": "-1"},
        page=page,
    )
    assert bad.status_code == 400  # the form again, as typed, the field marked beside it
    kept = form_state(bad.text, "assignment-settings")
    assert kept.values["title"] == "x" and kept.values["tolerance_heading_deg"] == "-1"
    assert kept.refused == ["tolerance_heading_deg"] and kept.autofocus == "tolerance_heading_deg"
    assert kept.errors == {"tolerance_heading_deg": "Type a number from 0 to 180."}
    with read_session() as db:  # nothing changed
        assert db.get(Assignment, world["assignment"]).title == "Find north v2"


def test_access_rules_for_review_routes(world):
    session_student = browser(world, "s1")
    session_id = start(session_student, world)
    do_lab(session_student, session_id)
    submit(session_student, session_id)
    make_user("t2", Role.teacher)
    other_teacher = browser(world, "t2")
    base = f"/courses/{world['course']}/assignments/{world['assignment']}"
    gets = [base, f"{base}/export.csv", f"{base}/export.zip", f"/review/sessions/{session_id}"]
    for path in gets:
        assert other_teacher.get(path).status_code == 404, path
        assert session_student.get(path).status_code == 403, path
    token = csrf_from(other_teacher, "/")
    for path in (f"{base}/settings", f"/review/sessions/{session_id}/feedback"):
        assert (
            other_teacher.post(path, data={"csrf_token": token, "action": "release"}).status_code
            == 404
        )
    student_token = csrf_from(session_student, "/")
    assert (
        session_student.post(
            f"/review/sessions/{session_id}/feedback",
            data={"csrf_token": student_token, "grade": "A+", "action": "release"},
        ).status_code
        == 403
    )
    assert session_of(session_id).status == "submitted"
    # a classmate sees nothing of it
    classmate = browser(world, "s2")
    assert classmate.get(f"/lab/sessions/{session_id}").status_code == 404
    assert classmate.get(f"/lab/sessions/{session_id}/results.json").status_code == 404


def test_teacher_can_try_the_assignment_as_a_student(world):
    teacher = browser(world, "teacher1")
    session_id = start(teacher, world)
    do_lab(teacher, session_id)
    results = teacher.get(f"/lab/sessions/{session_id}/results.json").json()
    assert results["heading"]["theta_deg"] == pytest.approx(-10.753, abs=1e-3)


def test_the_dashboards_cells_show_each_number_and_sort_by_it():
    """What the class table shows in its number cells and sorts them by (``data-value``):
    a heading error signed but sorted by its size, an empty cell a dash with no key."""
    from datetime import UTC, datetime
    from types import SimpleNamespace

    from app.review.dashboard_cells import EMPTY, row_cells
    from app.web.render import time_formatter

    errors = {"heading": -0.5549, "latitude": 1.2849, "earth_rate": None}
    row = SimpleNamespace(
        results={
            "heading": {"azimuth_deg": 181.4516},
            "latitude": {"latitude_deg": 40.4412, "earth_rate_deg_h": 15.10612},
        },
        submitted_at=datetime(2026, 11, 25, 1, 55, tzinfo=UTC),
        check_error=errors.get,
    )
    cells = row_cells(row, time_formatter("en", "Asia/Shanghai"))
    assert (cells.heading.text, cells.heading.value) == ("181.45°", "181.4516")
    assert (cells.heading_error.text, cells.heading_error.value) == ("-0.55°", "0.5549")
    assert (cells.latitude.text, cells.latitude_error.text) == ("40.44°", "1.28 %")
    assert (cells.earth_rate.text, cells.earth_rate.value) == ("15.106", "15.10612")
    assert (cells.earth_rate_error.text, cells.earth_rate_error.value) == (EMPTY, "")
    assert cells.submitted == type(cells.submitted)("Nov 25 09:55", "2026-11-25T01:55:00+00:00")
    chinese = row_cells(row, time_formatter("zh-CN", "Asia/Shanghai")).submitted.text
    assert chinese == "11月25日 09:55"  # the course's wall clock, its zone in the heading
    nothing = row_cells(
        SimpleNamespace(results={}, submitted_at=None, check_error=lambda _: None),
        time_formatter("en", None),
    )
    assert {getattr(nothing, name) for name in nothing.__slots__} == {type(nothing.heading)()}
