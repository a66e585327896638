"""Lab partners: a group shares one session of an assignment that allows groups."""

from __future__ import annotations

import re

from sqlmodel import select

from app.db import read_session, write_session
from app.models import Assignment, Attempt, LabSession, Role, SessionMember
from tests.factories import (
    HEADING,
    VERTICAL,
    browser,
    do_lab,
    make_course,
    make_user,
    post_form,
    review,
    save_manual,
    start,
    submit,
    token_for,
)


def allow_groups(world, size: int = 2) -> None:
    with write_session() as db:
        assignment = db.get(Assignment, world["assignment"])
        assignment.group_size = size
        db.add(assignment)


def code_of(session_id: int) -> str:
    with read_session() as db:
        return db.get(LabSession, session_id).partner_code


def join(client, code: str):
    return post_form(client, "/lab/join-group", {"code": code}, page="/lab")


def flash_of(client, path: str = "/lab") -> str:
    return client.get(path).text


def test_partners_share_record_submit_and_get_one_grade(world):
    allow_groups(world)
    s1, s2 = browser(world, "s1"), browser(world, "s2")
    session_id = start(s1, world)
    code = code_of(session_id)
    assert re.fullmatch(r"[A-HJ-NP-Z2-9]{6}", code)
    assert code in s1.get(f"/lab/sessions/{session_id}").text
    response = join(s2, f"  {code.lower()} ")
    assert response.headers["location"] == f"/lab/sessions/{session_id}"
    assert start(s2, world) == session_id  # "Start" leads a partner to the group's session
    # the partner records part A, the starter part B: one session
    save_manual(s2, session_id, "heading", HEADING)
    save_manual(s1, session_id, "latitude", VERTICAL)
    page = s1.get(f"/lab/sessions/{session_id}").text
    assert "学生2" in page and "n = 10" in page
    state = s2.get(f"/lab/sessions/{session_id}/state").json()
    assert state["status"] == "in_progress" and state["version"]
    submit(s2, session_id)  # either may submit, once for the group
    with read_session() as db:
        assert len(db.exec(select(Attempt)).all()) == 1
    teacher = browser(world, "teacher1")
    base = f"/courses/{world['course']}/assignments/{world['assignment']}"
    dashboard = teacher.get(base).text
    assert dashboard.count("group of 2") == 2  # both members' rows show the group
    assert "identical data" not in dashboard.lower()  # partners share data by design
    submission = teacher.get(f"/review/sessions/{session_id}").text
    assert 'id="group-members"' in submission and "学生2" in submission
    review(teacher, session_id, points="88", feedback="Good teamwork.", action="release")
    for client in (s1, s2):
        home = client.get("/").text
        assert "88 / 100" in home and 'id="notices"' in home
    # the API lists the shared session for the partner too
    sessions = s2.get("/api/v1/sessions", headers=token_for(s2, "s2")).json()
    assert [s["id"] for s in sessions] == [session_id]


def test_a_group_is_limited_and_consensual(world):
    allow_groups(world, 2)
    s1, s2, s3 = browser(world, "s1"), browser(world, "s2"), browser(world, "s3")
    session_id = start(s1, world)
    code = code_of(session_id)
    join(s2, code)
    join(s3, code)
    assert "This group is full (2 students)." in flash_of(s3)
    # a student of another course cannot join with a guessed or leaked code
    outsider = make_user("outsider", Role.student)
    other_teacher = make_user("teacher2", Role.teacher)
    make_course(other_teacher, "Other", (outsider,))
    stranger = browser(world, "outsider")
    join(stranger, code)
    assert "No group of your courses has this code." in flash_of(stranger)
    join(s3, "NOCODE")
    assert "No group of your courses has this code." in flash_of(s3)
    with read_session() as db:
        members = db.exec(select(SessionMember.user_id)).all()
    assert len(members) == 1


def test_leaving_only_before_recording(world):
    allow_groups(world, 3)
    s1, s2 = browser(world, "s1"), browser(world, "s2")
    session_id = start(s1, world)
    join(s2, code_of(session_id))
    page = f"/lab/sessions/{session_id}"
    assert post_form(s2, f"{page}/leave", page=page).headers["location"] == "/lab"
    assert s2.get(page).status_code == 404  # no longer theirs
    join(s2, code_of(session_id))
    save_manual(s1, session_id, "heading", HEADING)
    post_form(s2, f"{page}/leave", page=page)
    assert "Recording has started" in s2.get(page).text
    post_form(s1, f"{page}/leave", page=page)  # the starter stays with their session
    assert "stays with it" in s1.get(page).text


def test_own_work_is_never_thrown_away_by_joining(world):
    allow_groups(world)
    s1, s2 = browser(world, "s1"), browser(world, "s2")
    group = start(s1, world)
    own = start(s2, world)
    do_lab(s2, own)
    join(s2, code_of(group))
    assert "already recorded readings of your own" in flash_of(s2)
    s3 = browser(world, "s3")
    empty = start(s3, world)
    join(s3, code_of(group))
    with read_session() as db:
        assert db.get(LabSession, empty) is None  # an empty session of theirs is replaced
        assert db.get(LabSession, own) is not None


def test_no_groups_no_code(world):
    s1 = browser(world, "s1")
    session_id = start(s1, world)
    assert code_of(session_id) is None
    assert 'id="partners"' not in s1.get(f"/lab/sessions/{session_id}").text
    assert 'id="join-group"' not in s1.get("/lab").text
