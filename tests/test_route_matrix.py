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

from app.db import read_session, write_session
from app.models import (
    ApiToken,
    BoardSnapshot,
    LtiContext,
    LtiPlatform,
    LtiResourceLink,
    ReadingArchive,
    ReportJob,
    Role,
    User,
)
from app.routes import iter_routes
from tests.conftest import snapshot
from tests.factories import (
    ACCESS,
    JSON_BODIES,
    RAW_BODIES,
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
    platform_id, link_id = placed_in_an_lms(world)
    with write_session() as db:  # a finished zip of the class's reports
        teacher_id = db.exec(select(User.id).where(User.username == "teacher1")).one()
        job = ReportJob(
            assignment_id=world["assignment"],
            requester_id=teacher_id,
            language="en",
            status="done",
            content=b"PK\x05\x06" + bytes(18),
        )
        db.add(job)
        snapshot = BoardSnapshot(assignment_id=world["assignment"], data='{"groups": []}')
        db.add(snapshot)
        archive = ReadingArchive(teacher_id=teacher_id, name="2025.zip", groups=1)
        db.add(archive)
        db.flush()
        job_id, snapshot_id, archive_id = job.id, snapshot.id, archive.id
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
        "platform_id": platform_id,
        "link_id": link_id,
        "token": "not-a-token",
        "job_id": job_id,
        "snapshot_id": snapshot_id,
        "archive_id": archive_id,
    }


def placed_in_an_lms(world) -> tuple[int, int]:
    """The world's assignment as an activity of a registered LMS (for the LTI routes)."""
    with write_session() as db:
        platform = LtiPlatform(
            name="LMS",
            issuer="https://lms.example",
            client_id="c",
            auth_login_url="https://lms.example/auth",
            auth_token_url="https://lms.example/token",
            key_set_url="https://lms.example/jwks",
        )
        db.add(platform)
        db.flush()
        context = LtiContext(platform_id=platform.id, context_id="c1", course_id=world["course"])
        db.add(context)
        db.flush()
        link = LtiResourceLink(
            platform_id=platform.id,
            resource_link_id="r1",
            context_row_id=context.id,
            assignment_id=world["assignment"],
        )
        db.add(link)
        db.flush()
        return platform.id, link.id


def routes_with(*rules: str) -> list[str]:
    return sorted(r for r, rule in ACCESS.items() if rule in rules)


# Each check walks its routes with one client and reports every route that fails (a refused
# request changes nothing, so the routes cannot disturb one another).


def stream_refused(client, path: str, headers: dict | None = None) -> bool:
    """Whether the WebSocket is closed on us.  A start request is sent first, so an accepted
    socket answers (a frame) instead of waiting for one forever."""
    start = {"action": "start", "part": "heading", "position": 1, "dwell_s": 1, "speed": 100}
    try:
        with client.websocket_connect(path, headers=headers or {}) as ws:
            ws.send_json(start)
            ws.receive_json()
    except WebSocketDisconnect:
        return True
    return False


@pytest.mark.sqlite_only
def test_anonymous_is_refused(ids):
    wrong = []
    with TestClient(ids["app"], follow_redirects=False) as anonymous:
        for route in sorted(r for r, rule in ACCESS.items() if rule != "public"):
            method, path = concrete(route, ids)
            if method == "WS":
                if not stream_refused(anonymous, path):
                    wrong.append((route, "accepted"))
                continue
            response = request(anonymous, method, path)
            json_route = method == "POST" and path.endswith((*JSON_BODIES, *RAW_BODIES))
            if path.startswith("/api/") or json_route:
                if response.status_code != 401:  # JSON callers get JSON, not a redirect
                    wrong.append((route, response.status_code))
            elif response.status_code != 303 or "/login" not in response.headers["location"]:
                wrong.append((route, response.status_code))
    assert wrong == []


@pytest.mark.sqlite_only
def test_students_are_refused_teacher_routes(ids):
    wrong = []
    with TestClient(ids["app"], follow_redirects=False) as student:
        login(student, "s1")
        api = token_for(student, "s1")
        for route in routes_with("teacher", "teacher-any", "review"):
            method, path = concrete(route, ids)
            headers = api if path.startswith("/api/") else {}
            response = request(student, method, path, headers)
            if response.status_code != 403 or "学生2" in response.text:  # no classmate's data
                wrong.append((route, response.status_code))
    assert wrong == []


@pytest.mark.sqlite_only
@pytest.mark.parametrize("route", routes_with("admin"))
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


def test_other_teachers_get_404(ids):
    make_user("t2", Role.teacher)
    wrong = []
    with TestClient(ids["app"], follow_redirects=False) as other:
        login(other, "t2")
        api = token_for(other, "t2")
        for route in routes_with("teacher", "review"):
            method, path = concrete(route, ids)
            response = request(other, method, path, api if path.startswith("/api/") else {})
            if response.status_code != 404:
                wrong.append((route, response.status_code))
    assert wrong == []


def test_a_teacher_sharing_the_student_reaches_nothing_of_the_other_course(ids):
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
    wrong = []
    with TestClient(ids["app"], follow_redirects=False) as other:
        login(other, "t2")
        api = token_for(other, "t2")
        for route in routes_with("teacher", "review"):
            method, path = concrete(route, ids)
            response = request(other, method, path, api if path.startswith("/api/") else {})
            api_reset = path.endswith("/reset-password") and path.startswith("/api/")
            if response.status_code != (403 if api_reset else 404):
                wrong.append((route, response.status_code))
    assert wrong == []
    with read_session() as db:
        assert db.get(User, ids["student_id"]).password_hash == before


def test_other_students_get_404(ids):
    wrong = []
    with TestClient(ids["app"], follow_redirects=False) as other:
        login(other, "s2")
        api = token_for(other, "s2")
        for route in routes_with("owner", "token"):
            method, path = concrete(route, ids)
            if method == "WS":
                if not stream_refused(other, path, {"origin": "http://testserver"}):
                    wrong.append((route, "accepted"))
                continue
            response = request(other, method, path, api if path.startswith("/api/") else {})
            if response.status_code != 404:
                wrong.append((route, response.status_code))
    assert wrong == []
