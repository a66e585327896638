"""Who may reach what: students, teachers, other teachers, anonymous visitors."""

from __future__ import annotations

import pytest

from app.models import Role
from tests.factories import csrf_from, login, make_course, make_user, without_tokens

TEACHER_GETS = ["/courses/{course}"]
TEACHER_POSTS = [
    "/courses/{course}/rename",
    "/courses/{course}/archive",
    "/courses/{course}/students",
    "/courses/{course}/import",
    "/courses/{course}/students/{student}/reset-password",
    "/courses/{course}/students/{student}/remove",
]


@pytest.fixture
def world(teacher):
    student = make_user("s1", Role.student)
    other_teacher = make_user("t2", Role.teacher)
    course = make_course(teacher, "A", (student,))
    return {"course": course, "student": student.id, "other_teacher": other_teacher}


def fill(path, world):
    return path.format(course=world["course"], student=world["student"])


def test_anonymous_is_redirected_to_login(client, world):
    for path in ["/", "/account/password", *TEACHER_GETS]:
        response = client.get(fill(path, world))
        assert response.status_code == 303 and "/login" in response.headers["location"]


def test_anonymous_posts_are_refused(client, world):
    client.get("/login")
    token = client.cookies["gyrolab_csrf"]
    for path in ["/courses", *TEACHER_POSTS]:
        response = client.post(fill(path, world), data={"csrf_token": token, "name": "x"})
        assert response.status_code == 303 and "/login" in response.headers["location"]


def test_student_cannot_reach_teacher_pages(client, world):
    login(client, "s1")
    token = csrf_from(client, "/")
    for path in TEACHER_GETS:
        assert client.get(fill(path, world)).status_code == 403
    for path in ["/courses", *TEACHER_POSTS]:
        response = client.post(
            fill(path, world),
            data={"csrf_token": token, "name": "x", "username": "zz", "display_name": "z"},
        )
        assert response.status_code == 403, path
        assert "do not have access" in response.text


def test_teacher_cannot_reach_another_teachers_course(client, world):
    login(client, "t2")
    token = csrf_from(client, "/")
    for path in TEACHER_GETS:
        response = client.get(fill(path, world))
        assert response.status_code == 404
        assert "s1" not in without_tokens(response.text)
    for path in TEACHER_POSTS:
        response = client.post(
            fill(path, world),
            data={"csrf_token": token, "name": "x", "username": "zz", "display_name": "z"},
        )
        assert response.status_code == 404, path
    assert "A" not in [line.strip() for line in client.get("/").text.splitlines()]


def test_teacher_cannot_touch_a_student_outside_the_course(client, world, teacher):
    outsider = make_user("outsider", Role.student)
    login(client, "teacher1")
    token = csrf_from(client, "/")
    course = world["course"]
    for action in ("reset-password", "remove"):
        response = client.post(
            f"/courses/{course}/students/{outsider.id}/{action}", data={"csrf_token": token}
        )
        assert response.status_code == 404


def test_unknown_course_is_404(client, world):
    login(client, "teacher1")
    assert client.get("/courses/99999").status_code == 404
