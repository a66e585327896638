"""A student's account is theirs alone: consent to enrolment, who may reset a password,
administrators, and credentials that end every old session and token."""

from __future__ import annotations

import re
import subprocess
import sys

import pytest
from fastapi.testclient import TestClient
from sqlmodel import select

from app.accounts.security import verify_password
from app.db import read_session
from app.models import ApiToken, Course, Enrollment, Role, User
from tests.factories import (
    API,
    PASSWORD,
    credentials_from,
    csrf_from,
    import_file,
    login,
    make_course,
    make_user,
    post_form,
    section,
    token_for,
)


def enrolled(username: str, course_id: int) -> bool:
    with read_session() as db:
        user = db.exec(select(User).where(User.username == username)).one()
        found = db.exec(
            select(Enrollment).where(
                Enrollment.student_id == user.id, Enrollment.course_id == course_id
            )
        ).first()
    return found is not None


def user_named(username: str) -> User:
    with read_session() as db:
        return db.exec(select(User).where(User.username == username)).one()


def join_code(course_id: int) -> str:
    with read_session() as db:
        return db.get(Course, course_id).join_code


def signed_in(app, username: str) -> TestClient:
    client = TestClient(app, follow_redirects=False)
    assert login(client, username).status_code == 303
    return client


def setup_two_teachers(app):
    """teacher1's roster created student1 (in course A); teacher2 has an empty course B."""
    teacher1 = make_user("teacher1", Role.teacher)
    teacher2 = make_user("teacher2", Role.teacher)
    student = make_user("student1", created_by=teacher1)
    course_a = make_course(teacher1, "A", (student,))
    course_b = make_course(teacher2, "B")
    return course_a, course_b, signed_in(app, "teacher2")


def test_another_teacher_cannot_add_an_existing_student_by_name(app):
    _, course_b, teacher2 = setup_two_teachers(app)
    response = post_form(
        teacher2,
        f"/courses/{course_b}/students",
        {"username": "student1", "display_name": "Anyone", "email": ""},
        page=f"/courses/{course_b}",
    )
    assert response.status_code == 400
    assert join_code(course_b) in response.text  # the page says how the student joins
    assert not enrolled("student1", course_b)


def test_another_teachers_roster_import_does_not_enroll_an_existing_student(app):
    _, course_b, teacher2 = setup_two_teachers(app)
    response = import_file(teacher2, course_b, b"student1,X\nnew1,Y\n")
    assert response.status_code == 200
    assert set(credentials_from(response.text)) == {"new1"}
    assert "student1" in section(response.text, "needs-code")
    assert not enrolled("student1", course_b) and enrolled("new1", course_b)


def test_the_takeover_of_the_report_is_closed(app):
    """The reported attack: teacher2 enrols student1, resets the password, logs in as them."""
    course_a, course_b, teacher2 = setup_two_teachers(app)
    student = user_named("student1")
    # even once the student has joined teacher2's course by consent...
    pupil = signed_in(app, "student1")
    assert post_form(pupil, "/join", {"code": join_code(course_b)}).status_code == 303
    assert enrolled("student1", course_b)
    # ...teacher2 may not reset the password (teacher1's roster created the account)
    page = teacher2.get(f"/courses/{course_b}")
    assert f"/students/{student.id}/reset-password" not in page.text
    response = post_form(
        teacher2, f"/courses/{course_b}/students/{student.id}/reset-password", page="/"
    )
    assert response.status_code == 303
    assert "administrator" in teacher2.get(response.headers["location"]).text
    assert verify_password(PASSWORD, user_named("student1").password_hash)
    # and teacher1, the creator, no longer may either: another teacher's course holds it
    teacher1 = signed_in(app, "teacher1")
    post_form(teacher1, f"/courses/{course_a}/students/{student.id}/reset-password", page="/")
    assert verify_password(PASSWORD, user_named("student1").password_hash)
    assert pupil.get("/").status_code == 200  # the student's session lives on


def test_the_creator_resets_while_no_other_course_holds_the_student(app):
    course_a, _, _ = setup_two_teachers(app)
    student = user_named("student1")
    teacher1 = signed_in(app, "teacher1")
    response = post_form(
        teacher1, f"/courses/{course_a}/students/{student.id}/reset-password", page="/"
    )
    assert response.status_code == 200
    new = credentials_from(response.text)["student1"]
    assert verify_password(new, user_named("student1").password_hash)


def test_join_by_code_and_link(app):
    _, course_b, _ = setup_two_teachers(app)
    pupil = signed_in(app, "student1")
    code = join_code(course_b)
    link = pupil.get(f"/join?code={code.lower()}")
    assert link.status_code == 200 and "“B”" in link.text
    assert post_form(pupil, "/join", {"code": "NOPE1234"}).status_code == 400
    assert not enrolled("student1", course_b)
    spaced = f" {code[:4]} {code[4:].lower()} "
    assert post_form(pupil, "/join", {"code": spaced}).status_code == 303
    assert enrolled("student1", course_b)
    # a new code ends the old one
    teacher2 = signed_in(app, "teacher2")
    post_form(teacher2, f"/courses/{course_b}/join-code", page=f"/courses/{course_b}")
    assert join_code(course_b) != code
    make_user("student9")
    other = signed_in(app, "student9")
    assert post_form(other, "/join", {"code": code}).status_code == 400
    # the new code with a dash in it, in a Chinese input method's full-width forms
    new = join_code(course_b)
    typed = "".join(chr(ord(c) + 0xFEE0) for c in f"{new[:4]}-{new[4:]}".lower())
    assert post_form(other, "/join", {"code": typed}).status_code == 303
    assert enrolled("student9", course_b)


def test_teachers_do_not_join_courses(app):
    _, course_b, _ = setup_two_teachers(app)
    teacher1 = signed_in(app, "teacher1")
    assert teacher1.get(f"/join?code={join_code(course_b)}").status_code == 403


def test_api_reset_follows_the_same_rule(app, client):
    course_a, course_b, _ = setup_two_teachers(app)
    student = user_named("student1")
    path = f"{API}/users/{student.id}/reset-password"
    assert client.post(path, headers=token_for(client, "teacher2")).status_code == 404
    assert client.post(path, headers=token_for(client, "student1")).status_code == 403
    pupil = signed_in(app, "student1")
    post_form(pupil, "/join", {"code": join_code(course_b)})
    refused = client.post(path, headers=token_for(client, "teacher2"))
    assert refused.status_code == 403 and "administrator" in refused.json()["detail"]
    assert client.post(path, headers=token_for(client, "teacher1")).status_code == 403
    make_user("root", Role.admin)
    done = client.post(path, headers=token_for(client, "root"))
    assert done.status_code == 200
    assert verify_password(done.json()["initial_password"], user_named("student1").password_hash)


def test_admin_page_lists_creates_and_resets(app):
    setup_two_teachers(app)
    make_user("root", Role.admin)
    admin = signed_in(app, "root")
    assert admin.get("/").headers["location"] == "/admin/accounts"
    page = admin.get("/admin/accounts?q=student")
    listed = re.findall(r"<td><code>([^<]+)</code>", page.text)
    assert page.status_code == 200 and listed == ["student1"]
    page = admin.get("/admin/accounts?q=ｓｔｕｄｅｎｔ１")  # typed in full-width forms
    assert re.findall(r"<td><code>([^<]+)</code>", page.text) == ["student1"]
    created = post_form(
        admin,
        "/admin/accounts",
        {"username": "wang", "display_name": "王老师", "role": "teacher"},
        page="/admin/accounts",
    )
    assert created.status_code == 200
    first = re.search(r'class="secret">([^<]+)<', created.text).group(1)
    assert user_named("wang").role == "teacher" and user_named("wang").must_change_password
    assert verify_password(first, user_named("wang").password_hash)
    student = user_named("student1")
    reset = post_form(admin, f"/admin/accounts/{student.id}/reset-password", page="/admin/accounts")
    assert reset.status_code == 200
    new = re.search(r'class="secret">([^<]+)<', reset.text).group(1)
    assert verify_password(new, user_named("student1").password_hash)
    root = user_named("root")
    refused = post_form(admin, f"/admin/accounts/{root.id}/reset-password", page="/admin/accounts")
    assert refused.status_code == 403
    bad = post_form(
        admin,
        "/admin/accounts",
        {"username": "x y", "display_name": "n", "role": "teacher"},
        page="/admin/accounts",
    )
    assert bad.status_code == 400


def test_teachers_and_students_are_refused_the_admin_pages(app):
    setup_two_teachers(app)
    for username in ("teacher1", "student1"):
        client = signed_in(app, username)
        assert client.get("/admin/accounts").status_code == 403
        assert post_form(client, "/admin/accounts", {"username": "z"}).status_code == 403


@pytest.mark.slow
def test_cli_creates_an_administrator(var_dir):
    command = [sys.executable, "-m", "app.cli.main", "create-user", "--role", "admin"]
    result = subprocess.run(
        [*command, "--username", "root", "--display-name", "Root"],
        input="a-long-password-1\n",
        capture_output=True,
        text=True,
    )
    assert result.returncode == 0, result.stderr
    assert user_named("root").role == "admin"


# --- credentials changed: every old session and token is dead --------------------------------


def personal_token(client) -> dict[str, str]:
    page = client.post(
        "/account/tokens",
        data={
            "csrf_token": csrf_from(client, "/account/tokens"),
            "name": "bridge",
            "scopes": ["read", "upload"],
        },
    )
    raw = re.search(r'id="new-token">([^<]+)<', page.text).group(1)
    return {"Authorization": f"Bearer {raw}"}


def test_password_change_ends_other_sessions_and_every_token(app, client):
    make_user("student1")
    other_browser = signed_in(app, "student1")
    browser = signed_in(app, "student1")
    pat = personal_token(browser)
    hour = token_for(client, "student1")
    assert client.get(f"{API}/me", headers=pat).status_code == 200
    response = post_form(
        browser,
        "/account/password",
        {
            "current_password": PASSWORD,
            "new_password": "another-secret-9",
            "confirm_password": "another-secret-9",
        },
        page="/account/password",
    )
    assert response.status_code == 303
    assert browser.get("/").status_code == 200  # the one who changed it stays logged in
    assert other_browser.get("/").status_code == 303  # every other session ended
    assert client.get(f"{API}/me", headers=pat).status_code == 401
    assert client.get(f"{API}/me", headers=hour).status_code == 401
    with read_session() as db:
        assert all(t.revoked_at is not None for t in db.exec(select(ApiToken)).all())


def test_a_reset_ends_every_session_and_token(app, client):
    teacher = make_user("teacher1", Role.teacher)
    student = make_user("student1", created_by=teacher)
    course = make_course(teacher, "A", (student,))
    pupil = signed_in(app, "student1")
    pat = personal_token(pupil)
    hour = token_for(client, "student1")
    teacher_browser = signed_in(app, "teacher1")
    post_form(teacher_browser, f"/courses/{course}/students/{student.id}/reset-password", page="/")
    assert pupil.get("/").status_code == 303
    for headers in (pat, hour):
        assert client.get(f"{API}/me", headers=headers).status_code == 401


def test_bearer_caller_who_must_change_the_password_is_refused(app, client):
    make_user("student1")
    browser = signed_in(app, "student1")
    pat = personal_token(browser)
    with read_session() as db:  # e.g. set by an import tool, without a reset
        user = db.exec(select(User).where(User.username == "student1")).one()
    from app.db import write_session

    with write_session() as db:
        row = db.get(User, user.id)
        row.must_change_password = True
        db.add(row)
    refused = client.get(f"{API}/me", headers=pat)
    assert refused.status_code == 403 and "password" in refused.json()["detail"]
