"""The grading desk: reviews per attempt, points and rubric, bulk release, notices,
next/previous student, extensions, the course's time zone, the teacher's wording."""

from __future__ import annotations

import csv
import io
import json
import re
import sqlite3
from datetime import UTC, datetime, timedelta

import pytest
from sqlmodel import select

from app.core.exceptions import UserError
from app.db import read_session, write_session
from app.models import (
    Assignment,
    Attempt,
    Course,
    Extension,
    GradeAmendment,
    LabSession,
    utcnow,
)
from tests.factories import (
    browser,
    csrf_from,
    do_lab,
    form_state,
    post_form,
    review,
    set_assignment,
    start,
    submit,
    without_tokens,
)


def submitted(world, username: str) -> tuple[object, int]:
    client = browser(world, username)
    session_id = start(client, world)
    do_lab(client, session_id)
    submit(client, session_id)
    return client, session_id


def status_of(session_id: int) -> str:
    with read_session() as db:
        return db.get(LabSession, session_id).status


def latest(session_id: int) -> Attempt:
    with read_session() as db:
        return db.exec(
            select(Attempt).where(Attempt.session_id == session_id).order_by(Attempt.number.desc())
        ).first()


def test_points_are_checked_against_the_maximum(world):
    teacher = browser(world, "teacher1")
    _, session_id = submitted(world, "s1")
    page = f"/review/sessions/{session_id}"
    typed = {"feedback": "Careful work 认真", "comment-latitude-2": "Let the table settle."}
    for bad in ("101", "-1", "nan", "inf", "1e400", "abc"):
        for action in ("save", "release"):
            answer = review(teacher, session_id, points=bad, action=action, **typed)
            # issue 34: the page again, with everything the teacher typed kept
            assert answer.status_code == 400
            assert "Points: enter a number from 0 to 100" in answer.text
            assert "Careful work 认真</textarea>" in answer.text
            assert 'value="Let the table settle."' in answer.text
            assert f'value="{bad}" aria-invalid="true"' in answer.text
            assert latest(session_id).points is None and not latest(session_id).feedback
            assert status_of(session_id) == "submitted"
    review(teacher, session_id, points="87,5", letter="B+", action="save")  # decimal comma
    assert latest(session_id).points == 87.5 and latest(session_id).letter == "B+"
    assert status_of(session_id) == "submitted"  # saved, not released
    assert "87.5 / 100 (B+)" in teacher.get(page).text
    review(teacher, session_id, points="８８．５", action="save")  # a Chinese input method's
    assert latest(session_id).points == 88.5


def test_a_rubric_sums_its_criteria(world):
    teacher = browser(world, "teacher1")
    base = f"/courses/{world['course']}/assignments/{world['assignment']}"
    form = {
        "title": "Find north",
        "latitude_deg": "39.93",
        "methods": ["manual", "csv", "simulator"],
        "max_points": "50",
        "rubric": "Heading within tolerance | 30\n纬度与地速 ｜ ２０",
    }
    post_form(teacher, f"{base}/settings", form, page=base)
    with read_session() as db:
        rubric = json.loads(db.get(Assignment, world["assignment"]).rubric)
    assert rubric == [
        {"name": "Heading within tolerance", "points": 30.0},
        {"name": "纬度与地速", "points": 20.0},
    ]
    # a rubric that does not add up to the maximum is refused with a clear message
    refused = post_form(teacher, f"{base}/settings", {**form, "max_points": "60"}, page=base)
    assert refused.status_code == 400 and "add up to 50, not the maximum 60" in refused.text
    refused = post_form(teacher, f"{base}/settings", {**form, "rubric": "no points"}, page=base)
    assert refused.status_code == 400 and "Rubric line 1" in refused.text
    _, session_id = submitted(world, "s1")
    page = teacher.get(f"/review/sessions/{session_id}").text
    assert 'name="rubric-0"' in page and 'name="points"' not in page
    answer = review(teacher, session_id, **{"rubric-0": "31", "rubric-1": "20"}, action="save")
    assert "Heading within tolerance: enter a number from 0 to 30" in answer.text  # above 30
    assert 'name="rubric-0" inputmode="decimal" value="31" aria-label' in answer.text
    assert 'value="31" aria-label="Heading within tolerance" aria-invalid="true"' in answer.text
    assert 'value="20" aria-label="纬度与地速">' in answer.text  # the other criterion kept
    review(teacher, session_id, **{"rubric-0": "25"}, action="release")  # one criterion open
    assert status_of(session_id) == "submitted" and latest(session_id).points is None
    review(teacher, session_id, **{"rubric-0": "25", "rubric-1": "１７。５"}, action="release")
    assert status_of(session_id) == "graded"
    assert latest(session_id).points == 42.5
    assert json.loads(latest(session_id).rubric_points) == {"0": 25.0, "1": 17.5}


def test_bulk_release_releases_only_graded_submissions(world):
    teacher = browser(world, "teacher1")
    s1, first = submitted(world, "s1")
    _, second = submitted(world, "s2")
    _, third = submitted(world, "s3")
    review(teacher, first, points="90", feedback="Well done.", action="save")
    review(teacher, second, points="70", action="save")  # third: no points yet
    base = f"/courses/{world['course']}/assignments/{world['assignment']}"
    dashboard = teacher.get(base).text
    assert "Release 2 graded" in dashboard
    response = post_form(
        teacher,
        f"{base}/release",
        {"session": [str(first), str(second), str(third), "x"]},
        page=base,
    )
    assert response.status_code == 303
    assert [status_of(i) for i in (first, second, third)] == ["graded", "graded", "submitted"]
    assert "Released 2 graded submission(s); 1 skipped" in teacher.get(base).text
    # a student of another teacher's course cannot be released through this assignment
    assert (
        post_form(teacher, f"{base}/release", {"session": ["999999"]}, page=base).status_code == 303
    )
    # the student's dashboard announces it until the work is opened
    home = s1.get("/").text
    assert 'id="notices"' in home and "attempt 1 graded — 90 / 100" in home
    assert "Well done." in s1.get(f"/lab/sessions/{first}").text
    assert 'id="notices"' not in s1.get("/").text


def test_a_returned_review_is_announced_and_stays_during_the_fix(world):
    teacher = browser(world, "teacher1")
    student, session_id = submitted(world, "s1")
    review(teacher, session_id, feedback="Redo position 2.", action="return")
    assert "was returned for revision" in student.get("/").text
    page = student.get(f"/lab/sessions/{session_id}").text
    assert "Redo position 2." in page
    assert "was returned for revision" not in student.get("/").text  # read
    # the teacher sees the teacher's wording, not the student's
    submission = teacher.get(f"/review/sessions/{session_id}").text
    assert "You returned attempt 1 for revision" in submission
    assert "Your teacher returned this work" not in submission


def test_next_and_previous_student(world):
    teacher = browser(world, "teacher1")
    ids = [submitted(world, name)[1] for name in ("s1", "s2", "s3")]
    middle = teacher.get(f"/review/sessions/{ids[1]}").text
    assert f'href="/review/sessions/{ids[0]}"' in middle and f'href="/review/sessions/{ids[2]}"'
    assert "2 of 3" in middle
    first = teacher.get(f"/review/sessions/{ids[0]}").text
    assert 'id="previous-student"' not in first and 'id="next-student"' in first
    # save and go on to the next student
    response = review(teacher, ids[0], points="60", go="next")
    assert response.headers["location"] == f"/review/sessions/{ids[1]}"
    assert latest(ids[0]).points == 60


def test_an_extension_moves_one_students_due_date(world):
    set_assignment(world, due_at=utcnow() - timedelta(days=1), late_policy="refuse")
    teacher = browser(world, "teacher1")
    s1 = browser(world, "s1")
    session_id = start(s1, world)
    do_lab(s1, session_id)
    submit(s1, session_id)
    assert status_of(session_id) == "in_progress"  # refused: past due
    later = (datetime.now(UTC) + timedelta(days=2)).astimezone(
        __import__("zoneinfo").ZoneInfo("Asia/Shanghai")
    )
    page = f"/review/sessions/{session_id}"
    post_form(teacher, f"{page}/extension", {"due_at": later.strftime("%Y-%m-%dT%H:%M")}, page=page)
    with read_session() as db:
        extension = db.exec(select(Extension)).one()
    assert abs(extension.due_at - later.replace(second=0, microsecond=0)) < timedelta(seconds=1)
    submit(s1, session_id)
    assert status_of(session_id) == "submitted" and latest(session_id).late is False
    s2 = browser(world, "s2")  # the others' due date is unchanged
    other = start(s2, world)
    do_lab(s2, other)
    submit(s2, other)
    assert status_of(other) == "in_progress"
    assert (
        "extended"
        in teacher.get(f"/courses/{world['course']}/assignments/{world['assignment']}").text
    )
    refused = post_form(teacher, f"{page}/extension", {"due_at": "not a date"}, page=page)
    assert refused.status_code == 400  # the desk again, the date as typed, the message beside
    kept = form_state(refused.text, "extension-form")
    assert kept.values["due_at"] == "not a date" and kept.refused == ["due_at"]
    assert "not a date and time" in kept.errors["due_at"]
    post_form(teacher, f"{page}/extension", {"remove": "1"}, page=page)
    with read_session() as db:
        assert db.exec(select(Extension)).all() == []


def test_due_dates_are_typed_and_shown_in_the_courses_zone(world):
    teacher = browser(world, "teacher1")
    course_page = f"/courses/{world['course']}"
    post_form(teacher, f"{course_page}/timezone", {"timezone": "Europe/Berlin"}, page=course_page)
    refused = post_form(
        teacher, f"{course_page}/timezone", {"timezone": "Mars/Olympus"}, page=course_page
    )
    assert refused.status_code == 400 and "is not a time zone" in refused.text
    with read_session() as db:
        assert db.get(Course, world["course"]).timezone == "Europe/Berlin"
    base = f"{course_page}/assignments/{world['assignment']}"
    form = {
        "title": "Find north",
        "latitude_deg": "39.93",
        "methods": ["manual"],
        "due_at": "2026-12-01T23:59",
    }
    post_form(teacher, f"{base}/settings", form, page=base)
    with read_session() as db:
        due = db.get(Assignment, world["assignment"]).due_at
    assert due.replace(tzinfo=UTC) == datetime(2026, 12, 1, 22, 59, tzinfo=UTC)  # CET = UTC+1
    page = teacher.get(base).text
    assert 'value="2026-12-01T23:59"' in page and "23:59 Central European Time" in page
    # "UTC" as a word (a random CSRF token may hold the three letters inside it)
    assert not re.search(r"(?<![\w-])UTC(?![\w-])", without_tokens(page))
    student = browser(world, "s1")
    lab = student.get("/lab").text
    assert "23:59" in lab and " UTC" not in lab


def test_hostile_review_fields_never_break_the_pages(world):
    teacher = browser(world, "teacher1")
    student, session_id = submitted(world, "s1")
    fields = {
        "comment-x": "no part",
        "comment-heading-99": "no such position",
        "comment-heading-2": "<script>alert(1)</script>",
        "feedback": '=HYPERLINK("http://evil")' + "x" * 30_000,
        "letter": "A" * 200,
        "action": "return",
    }
    assert review(teacher, session_id, **fields).status_code == 303
    attempt = latest(session_id)
    assert json.loads(attempt.feedback_positions) == {"heading-2": "<script>alert(1)</script>"}
    assert len(attempt.feedback) == 20_000 and len(attempt.letter) == 32
    page = student.get(f"/lab/sessions/{session_id}")
    assert page.status_code == 200 and "<script>alert(1)</script>" not in page.text
    assert teacher.get(f"/review/sessions/{session_id}").status_code == 200
    # a teacher may still release returned work; after that the grade is final
    review(teacher, session_id, points="50", action="release")
    assert status_of(session_id) == "graded" and latest(session_id).points == 50
    review(teacher, session_id, points="100", action="save")
    assert latest(session_id).points == 50
    assert "grade is released" in teacher.get(f"/review/sessions/{session_id}").text


def test_export_and_api_carry_points(world):
    teacher = browser(world, "teacher1")
    _, session_id = submitted(world, "s1")
    review(teacher, session_id, points="77", letter="B", action="release")
    from tests.factories import token_for

    headers = token_for(browser(world, "teacher1"), "teacher1")
    api = teacher.get(f"/api/v1/assignments/{world['assignment']}/export.csv", headers=headers)
    rows = list(csv.DictReader(io.StringIO(api.text.lstrip("\ufeff"))))
    mine = next(row for row in rows if row["username"] == "s1")
    assert (mine["points"], mine["max_points"], mine["letter_grade"], mine["released"]) == (
        "77.0000",
        "100",
        "B",
        "yes",
    )
    submissions = teacher.get(
        f"/api/v1/assignments/{world['assignment']}/submissions", headers=headers
    ).json()
    row = next(r for r in submissions if r["username"] == "s1")
    assert (row["points"], row["max_points"], row["grade"], row["released"]) == (
        77.0,
        100.0,
        "77 / 100 (B)",
        True,
    )


def test_the_old_reviews_move_to_their_attempts(tmp_path):
    """0007 → 0008: a session's feedback and grade land on its latest attempt."""
    from alembic import command

    from app.migrate import alembic_config, upgrade_to_head

    url = f"sqlite:///{tmp_path / 'old.db'}"
    command.upgrade(alembic_config(url), "0007")
    connection = sqlite3.connect(tmp_path / "old.db")
    connection.executescript("""
        INSERT INTO user (username, display_name, role, password_hash, must_change_password,
                          created_at) VALUES ('s', 'S', 'student', 'x', 0, '2026-01-01');
        INSERT INTO lab_session (owner_id, title, latitude_deg, earth_rate_deg_h,
            heading_rotation, heading_start_deg, latitude_start_deg, latitude_step_deg,
            min_readings, simulator_preset, sim_seed, sim_azimuth_deg, sim_turns,
            sim_table_heading, sim_table_latitude, status, grade, feedback, feedback_positions,
            graded_at, created_at, updated_at, sim_clock_s, symmetric_order)
            VALUES (1, 'old', 40, 15.041, 'ccw', 0, 0, 90, 10, 'teaching-fog', 1, 30, 0, 1, 1,
                    'graded', '92', 'Nice.', '{"heading-1": "ok"}', '2026-02-01', '2026-01-01',
                    '2026-01-01', 0, 0);
        INSERT INTO attempt (session_id, number, take_ids, results_json, submitted_at, late)
            VALUES (1, 1, '', '{}', '2026-01-02', 0), (1, 2, '', '{}', '2026-01-03', 0);
    """)
    connection.commit()
    connection.close()
    upgrade_to_head(url)
    connection = sqlite3.connect(tmp_path / "old.db")
    rows = connection.execute(
        "SELECT number, feedback, feedback_positions, points, letter, released_at IS NOT NULL"
        " FROM attempt ORDER BY number"
    ).fetchall()
    connection.close()
    assert rows == [
        (1, "", "{}", None, None, 0),
        (2, "Nice.", '{"heading-1": "ok"}', 92.0, None, 1),
    ]


@pytest.mark.parametrize("zone", ["Asia/Shanghai", "America/New_York"])
def test_local_time_round_trip(zone):
    from app.web.local_time import local_input_to_utc, utc_to_local_input

    typed = datetime(2026, 3, 8, 9, 30)
    stored = local_input_to_utc(typed, zone)
    assert stored.tzinfo is not None and utc_to_local_input(stored, zone) == "2026-03-08T09:30"


def test_csrf_protects_the_desk(world):
    teacher = browser(world, "teacher1")
    _, session_id = submitted(world, "s1")
    csrf_from(teacher, f"/review/sessions/{session_id}")
    base = f"/courses/{world['course']}/assignments/{world['assignment']}"
    for path, data in (
        (f"{base}/release", {"session": str(session_id)}),
        (f"/review/sessions/{session_id}/extension", {"due_at": "2030-01-01T00:00"}),
        (f"/courses/{world['course']}/timezone", {"timezone": "UTC"}),
    ):
        assert teacher.post(path, data=data).status_code == 403
    assert status_of(session_id) == "submitted"
    with read_session() as db:
        assert db.exec(select(Extension)).all() == []


def test_a_released_grade_is_amended_with_a_reason_the_student_sees(world):
    teacher = browser(world, "teacher1")
    student, session_id = submitted(world, "s1")
    review(teacher, session_id, points="78", feedback="Good.", action="release")
    assert status_of(session_id) == "graded"
    student.get(f"/lab/sessions/{session_id}")  # seen
    assert latest(session_id).seen_at is not None
    # a change without a reason is refused, everything typed kept, nothing changed
    answer = review(teacher, session_id, points="87", feedback="Good, re-marked.", action="amend")
    assert answer.status_code == 400
    assert "Say why the grade changes" in answer.text
    assert "Good, re-marked.</textarea>" in answer.text and 'value="87"' in answer.text
    assert latest(session_id).points == 78
    # a plain save of a released review stays refused
    assert review(teacher, session_id, points="90", action="save").status_code == 303
    assert latest(session_id).points == 78
    # with a reason: the grade changes, the history keeps the old one, the student is told
    answer = review(
        teacher,
        session_id,
        points="87",
        feedback="Good, re-marked.",
        reason="Part B was marked against the wrong latitude.",
        action="amend",
    )
    assert answer.status_code == 303
    attempt = latest(session_id)
    assert attempt.points == 87 and attempt.feedback == "Good, re-marked."
    assert attempt.seen_at is None and status_of(session_id) == "graded"
    with read_session() as db:
        (change,) = db.exec(select(GradeAmendment)).all()
    assert (change.points_before, change.points_after) == (78, 87)
    assert change.feedback_before == "Good." and change.teacher_id is not None
    desk = teacher.get(f"/review/sessions/{session_id}").text
    assert "78 → 87" in desk and "wrong latitude" in desk
    page = student.get(f"/lab/sessions/{session_id}").text
    assert "87 / 100" in page and "78 → 87" in page
    assert "Part B was marked against the wrong latitude." in page
    # only a released grade is amended
    _, other = submitted(world, "s2")
    refused = review(teacher, other, points="50", reason="x", action="amend")
    assert refused.status_code == 409 and "Only a released grade can be amended" in refused.text
    assert latest(other).points is None


def test_an_amendment_by_any_caller_sends_the_new_score(world):
    """grading.amend owns its effects, as release does (called as a script would)."""
    from app.review import grading

    teacher = browser(world, "teacher1")
    _, session_id = submitted(world, "s1")
    review(teacher, session_id, points="40", action="release")
    with write_session() as db:
        session = db.get(LabSession, session_id)
        attempt = db.get(Attempt, latest(session_id).id)
        fixed = grading.Review("ok", {}, 45.0, {}, None)
        with pytest.raises(UserError):
            grading.amend(db, session, attempt, fixed, "  ", None)
        assert grading.amend(db, session, attempt, fixed, "typo", None) == 0  # no LMS here
    assert latest(session_id).points == 45
