"""Access matrix: every route, every role.  Adding a route without listing it here fails.

The role checks (anonymous, student, administrator) are decided from the log-in alone,
before any object is loaded, so they run on SQLite only; the object rules (owner, another
teacher, a teacher sharing the student) depend on queries and run on both databases."""

from __future__ import annotations

import pytest
from fastapi.routing import APIRoute, APIWebSocketRoute
from fastapi.testclient import TestClient
from sqlmodel import select
from starlette.websockets import WebSocketDisconnect

from app.db import read_session
from app.models import ApiToken, Role, User
from tests.conftest import iter_routes, snapshot
from tests.factories import (
    ACCESS,
    JSON_BODIES,
    browser,
    build_world,
    concrete,
    csrf_from,
    do_lab,
    login,
    make_course,
    make_user,
    new_session,
    request,
    submit,
    token_for,
)


# rule: public | user (any log-in) | teacher (own course) | owner (own session)
#       | review (teacher of the session's course) | token (own API token)
#       | admin (administrators only)
def app_routes(app) -> set[str]:
    found = set()
    for route in iter_routes(app.routes):
        if isinstance(route, APIWebSocketRoute):
            found.add(f"WS {route.path}")
        elif isinstance(route, APIRoute) or hasattr(route, "methods"):
            if route.path == "/openapi.json":
                continue
            path = route.path
            if path.startswith("/vendor/plotly-"):
                path = "/vendor/plotly-{version}.min.js"
            for method in route.methods - {"HEAD"}:
                found.add(f"{method} {path}")
    return found


def test_every_route_is_in_the_matrix(app):
    assert app_routes(app) == set(ACCESS)


@pytest.fixture
def ids(request, app) -> dict:
    """The matrix's world: s1's submitted session and API token in teacher1's course; built
    once per module and database, copied into each test's own database."""
    return {**snapshot(request, "route-matrix", lambda: build_ids(app)), "app": app}


def build_ids(app) -> dict:
    world = build_world(app, make_user("teacher1", Role.teacher, name="Teacher One"))
    student = browser(world, "s1")
    session_id = new_session(student, assignment_id=str(world["assignment"]))
    do_lab(student, session_id)
    submit(student, session_id)
    token = csrf_from(student, "/account/tokens")
    page = student.post(
        "/account/tokens", data={"csrf_token": token, "name": "t", "scopes": ["read", "upload"]}
    )
    assert page.status_code == 200
    with read_session() as db:
        token_id = db.exec(select(ApiToken.id)).first()
        student_id = db.exec(select(User.id).where(User.username == "s1")).one()
    return {
        "course_id": world["course"],
        "assignment_id": world["assignment"],
        "session_id": session_id,
        "student_id": student_id,
        "user_id": student_id,
        "token_id": token_id,
        "part": "heading",
        "position": 1,
        "version": "x",
    }


@pytest.mark.sqlite_only
@pytest.mark.parametrize("route", sorted(r for r, rule in ACCESS.items() if rule != "public"))
def test_anonymous_is_refused(ids, route):
    method, path = concrete(route, ids)
    with TestClient(ids["app"], follow_redirects=False) as anonymous:
        if method == "WS":
            with pytest.raises(WebSocketDisconnect), anonymous.websocket_connect(path) as ws:
                ws.receive_json()
            return
        response = request(anonymous, method, path)
    json_route = method == "POST" and any(path.endswith(s) for s in JSON_BODIES)
    if path.startswith("/api/") or json_route:
        assert response.status_code == 401, route  # JSON callers get JSON, not a redirect
    else:
        assert response.status_code == 303 and "/login" in response.headers["location"], route


@pytest.mark.sqlite_only
@pytest.mark.parametrize(
    "route", sorted(r for r, rule in ACCESS.items() if rule in ("teacher", "teacher-any", "review"))
)
def test_students_are_refused_teacher_routes(ids, route):
    method, path = concrete(route, ids)
    with TestClient(ids["app"], follow_redirects=False) as student:
        headers = {}
        if path.startswith("/api/"):
            headers = token_for(student, "s1")
        else:
            login(student, "s1")
        response = request(student, method, path, headers)
    assert response.status_code == 403, route
    assert "学生2" not in response.text  # no classmate's data on the refusal


@pytest.mark.sqlite_only
@pytest.mark.parametrize("route", sorted(r for r, rule in ACCESS.items() if rule == "admin"))
def test_only_administrators_reach_admin_routes(ids, route):
    method, path = concrete(route, ids)
    make_user("root", Role.admin)
    for username in ("s1", "teacher1", "root"):
        with TestClient(ids["app"], follow_redirects=False) as caller:
            login(caller, username)
            response = request(caller, method, path)
        if username == "root":  # reached (an empty form may be a 400, never a refusal)
            assert response.status_code not in (401, 403, 404), (route, response.status_code)
        else:
            assert response.status_code == 403, (route, username)


@pytest.mark.parametrize(
    "route", sorted(r for r, rule in ACCESS.items() if rule in ("teacher", "review"))
)
def test_other_teachers_get_404(ids, route):
    make_user("t2", Role.teacher)
    method, path = concrete(route, ids)
    with TestClient(ids["app"], follow_redirects=False) as other:
        headers = {}
        if path.startswith("/api/"):
            headers = token_for(other, "t2")
        else:
            login(other, "t2")
        response = request(other, method, path, headers)
    assert response.status_code == 404, route


@pytest.mark.parametrize(
    "route", sorted(r for r, rule in ACCESS.items() if rule in ("teacher", "review"))
)
def test_a_teacher_sharing_the_student_reaches_nothing_of_the_other_course(ids, route):
    """t2's own course holds s1 too (s1 joined it with its code): t2 still reaches none of
    teacher1's courses, assignments or reviews of s1, and may not reset s1's password
    (neither teacher's roster created the account: only an administrator may)."""
    from app.accounts.service import join_course
    from app.db import read_session, write_session
    from app.models import Course, User

    t2 = make_user("t2", Role.teacher)
    course = make_course(t2, "Other course")
    with write_session() as db:
        code = db.get(Course, course).join_code
        join_course(db, db.get(User, ids["student_id"]), code)
    with read_session() as db:
        before = db.get(User, ids["student_id"]).password_hash
    method, path = concrete(route, ids)
    with TestClient(ids["app"], follow_redirects=False) as other:
        headers = token_for(other, "t2") if path.startswith("/api/") else {}
        if not headers:
            login(other, "t2")
        response = request(other, method, path, headers)
    expected = 403 if path.endswith("/reset-password") and path.startswith("/api/") else 404
    assert response.status_code == expected, route
    with read_session() as db:
        assert db.get(User, ids["student_id"]).password_hash == before


@pytest.mark.parametrize(
    "route", sorted(r for r, rule in ACCESS.items() if rule in ("owner", "token"))
)
def test_other_students_get_404(ids, route):
    method, path = concrete(route, ids)
    with TestClient(ids["app"], follow_redirects=False) as other:
        if method == "WS":
            login(other, "s2")
            with (
                pytest.raises(WebSocketDisconnect),
                other.websocket_connect(path, headers={"origin": "http://testserver"}) as ws,
            ):
                ws.receive_json()
            return
        headers = {}
        if path.startswith("/api/"):
            headers = token_for(other, "s2")
        else:
            login(other, "s2")
        response = request(other, method, path, headers)
    assert response.status_code == 404, route
