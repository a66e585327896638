"""Issue 34: every form keeps what was typed when a field is refused, and shows every
problem at once beside its field, in the user's language, with the focus on the first.
Each form is submitted with one (or more) bad fields here; the assignment, practice
session and grading-desk forms have their own tests (test_lab, test_review,
test_grading_desk)."""

from __future__ import annotations

import pytest
from sqlmodel import select

from app.accounts.security import verify_password
from app.db import read_session
from app.models import Role, User
from tests.factories import (
    PASSWORD,
    create_course,
    csrf_from,
    form_state,
    login,
    make_user,
    post_form,
)


def test_the_roster_form_keeps_every_field_and_marks_each_refused_one(teacher_client):
    course_id = create_course(teacher_client)
    page = f"/courses/{course_id}"
    typed = {"username": "li si", "display_name": "李四", "email": "li@@example"}
    response = post_form(teacher_client, f"{page}/students", typed, page=page)
    assert response.status_code == 400
    kept = form_state(response.text, "add-student")
    assert kept.values == typed  # nothing typed is lost
    assert kept.refused == ["username", "email"] and kept.autofocus == "username"
    assert "“li si” is not a valid username" in kept.errors["username"]
    assert "“li@@example” is not an email address" in kept.errors["email"]
    assert "2 fields need a change" in response.text

    # a name left out, in Chinese
    typed = {"username": "lisi", "display_name": " ", "email": "li@example.org"}
    response = teacher_client.post(
        f"{page}/students",
        data={**typed, "csrf_token": csrf_from(teacher_client, page)},
        headers={"Accept-Language": "zh-CN"},
    )
    kept = form_state(response.text, "add-student")
    assert kept.values == typed and kept.refused == ["display_name"]
    assert kept.errors == {"display_name": "请填写学生姓名。"}


def test_a_teacher_account_cannot_be_added_and_the_form_says_so_beside_the_username(
    teacher_client,
):
    make_user("teacher2", Role.teacher, name="Other Teacher")
    course_id = create_course(teacher_client)
    page = f"/courses/{course_id}"
    typed = {"username": "teacher2", "display_name": "Someone", "email": ""}
    response = post_form(teacher_client, f"{page}/students", typed, page=page)
    assert response.status_code == 400
    kept = form_state(response.text, "add-student")
    assert kept.values == typed and kept.refused == ["username"]
    assert "is a teacher account" in kept.errors["username"]


def test_renaming_a_course_to_nothing_keeps_the_old_name_and_says_why(teacher_client):
    course_id = create_course(teacher_client, "Navigation lab")
    page = f"/courses/{course_id}"
    response = post_form(teacher_client, f"{page}/rename", {"name": "  "}, page=page)
    assert response.status_code == 400
    kept = form_state(response.text, "course-name")
    assert kept.refused == ["name"] and kept.errors == {"name": "Give the course a name."}
    assert "Navigation lab" in teacher_client.get(page).text  # unchanged


def test_a_bad_time_zone_is_refused_beside_the_zone(teacher_client):
    course_id = create_course(teacher_client)
    page = f"/courses/{course_id}"
    response = post_form(
        teacher_client, f"{page}/timezone", {"timezone": "Mars/Olympus"}, page=page
    )
    assert response.status_code == 400
    assert 'name="timezone" id="field-timezone" aria-invalid="true"' in response.text


def test_the_token_form_keeps_the_name_and_the_scopes_chosen(student_client):
    page = "/account/tokens"
    response = post_form(student_client, page, {"name": "bench PC", "scopes": "upload"}, page=page)
    assert response.status_code == 400
    kept = form_state(response.text, "token-form")
    assert kept.values == {"name": "bench PC", "scopes": ["upload"]}  # as chosen, not reset
    assert kept.errors == {"scopes": "Every token needs at least the read scope."}
    assert kept.autofocus == "scopes"

    response = post_form(student_client, page, {"name": "", "scopes": ["read"]}, page=page)
    kept = form_state(response.text, "token-form")
    assert kept.values == {"name": "", "scopes": ["read"]}
    assert kept.refused == ["name"] and kept.errors == {"name": "Give the token a name."}


@pytest.mark.parametrize(
    ("current", "new", "confirm", "refused"),
    [
        ("wrong-password", "a-good-new-one", "a-good-new-one", ["current_password"]),
        (PASSWORD, "short", "shorter", ["new_password", "confirm_password"]),
        (
            "wrong-password",
            "a-good-new-one",
            "a-different-one",
            ["current_password", "confirm_password"],
        ),
    ],
)
def test_the_password_form_names_every_problem_and_never_sends_a_password_back(
    student_client, current, new, confirm, refused
):
    page = "/account/password"
    typed = {"current_password": current, "new_password": new, "confirm_password": confirm}
    response = post_form(student_client, page, typed, page=page)
    assert response.status_code == 400
    kept = form_state(response.text, "password-form")
    assert kept.refused == refused and kept.autofocus == refused[0]
    assert all(kept.errors[name] for name in refused)
    for secret in (current, new, confirm):
        assert f'value="{secret}"' not in response.text
    assert "type them once more" in response.text
    with read_session() as db:  # unchanged
        stored = db.exec(select(User).where(User.username == "student1")).one()
        assert verify_password(PASSWORD, stored.password_hash)


def test_a_failed_log_in_keeps_the_username_and_focuses_the_password(client, student):
    token = csrf_from(client, "/login")
    response = client.post(
        "/login",
        data={"username": "student1", "password": "nope-nope", "csrf_token": token},
        headers={"Accept-Language": "zh-CN"},
    )
    assert response.status_code == 401
    kept = form_state(response.text, "login-form")
    assert kept.values == {"username": "student1", "password": ""}
    assert kept.autofocus == "password"
    assert 'aria-describedby="login-error"' in response.text and 'id="login-error"' in response.text


def test_the_admins_new_account_form_keeps_what_was_typed(client):
    make_user("root", Role.admin)
    assert login(client, "root").status_code == 303
    page = "/admin/accounts"
    typed = {"username": "bad name!", "display_name": "王五", "role": "teacher"}
    response = post_form(client, page, typed, page=page)
    assert response.status_code == 400
    kept = form_state(response.text, "new-account")
    assert kept.values == typed and kept.refused == ["username"]
    assert "is not a valid username" in kept.errors["username"]
