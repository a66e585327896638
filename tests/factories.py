"""Test factories and helpers: users, courses, sessions, logins, the review world.

Every test module imports its helpers from here (no test module imports another).
"""

from __future__ import annotations

import csv
import functools
import io
import json
import re
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from unittest import mock
from urllib.parse import unquote

from fastapi.testclient import TestClient

from app.db import write_session
from app.models import Assignment, Role, User

# --- from conftest.py ----------------------------------------


def pdf_text(content: bytes) -> str:
    """The text of every page of a PDF, with the names and contents of its attachments.

    The pages' text by PDFium (pypdfium2; pypdf's extraction gives the same words but took
    0.5 s a report), the attachments by pypdf."""
    import pypdfium2
    from pypdf import PdfReader

    document = pypdfium2.PdfDocument(content)
    try:
        pages = [page.get_textpage().get_text_range() for page in document]
    finally:
        document.close()
    text = "\n".join(pages).replace("\r\n", "\n")
    reader = PdfReader(io.BytesIO(content))
    for name, blobs in reader.attachments.items():
        text += "\n" + name + "\n" + "".join(b.decode("utf-8", "replace") for b in blobs)
    return text


PASSWORD = "correct-horse-42"


@functools.cache
def english(error) -> str:
    """A UserError's words as an English reader sees them (from the catalogue)."""
    from app.web.i18n import translate

    return translate(error.key, "en", **error.params)


def password_hash_of_password() -> str:
    """One real argon2id hash of PASSWORD per test process: hashing it afresh for every
    account a test makes cost ~25 ms each, about a third of the quick loop (the log-ins
    still verify it the real way)."""
    from app.accounts.security import hash_password

    return hash_password(PASSWORD)


CSRF_RE = re.compile(r'name="csrf_token" value="([^"]+)"')


def make_user(
    username: str,
    role: Role = Role.student,
    *,
    must_change: bool = False,
    name: str = "",
    created_by: User | None = None,
) -> User:
    """An account with the password PASSWORD (``created_by``: the teacher whose roster made it)."""
    from app.accounts import service

    with (
        write_session() as db,
        mock.patch.object(service, "hash_password", lambda _password: password_hash_of_password()),
    ):
        return service.create_user(
            db,
            username=username,
            display_name=name or username.title(),
            role=role,
            password=PASSWORD,
            must_change_password=must_change,
            created_by=created_by,
        )


def make_course(teacher: User, name: str = "Lab", students: tuple[User, ...] = ()) -> int:
    from app.accounts.service import enroll
    from app.models import Course

    with write_session() as db:
        course = Course(name=name, teacher_id=teacher.id)
        db.add(course)
        db.flush()
        for student in students:
            enroll(db, course, student)
        return course.id


HIDDEN_INPUT_RE = re.compile(r'<input type="hidden"[^>]*>')


def without_tokens(page: str) -> str:
    """The page without its hidden inputs, where random CSRF tokens live: a test that a
    short string is absent must not fail when a random token happens to contain it."""
    return HIDDEN_INPUT_RE.sub("", page)


def csrf_from(client: TestClient, path: str) -> str:
    response = client.get(path)
    match = CSRF_RE.search(response.text)
    assert match, f"no CSRF token on {path} ({response.status_code})"
    return match.group(1)


def _form_token(client: TestClient, page: str) -> str:
    """The CSRF token a form on ``page`` carries.  A logged-in session's token is the
    session's own, so while the client's cookies (session, CSRF, pending flash) are
    unchanged the token last read is the one the page would show: re-rendering a page
    only to read it again cost ~35 ms a form.  Any cookie changed (a log-in, a flash
    waiting to be shown) reads the page, as the browser would."""
    cookies = tuple(sorted((c.name, c.value) for c in client.cookies.jar))
    cache = client.__dict__.setdefault("_form_tokens", {})
    token = cache.get(cookies)
    if token is None:
        token = cache[cookies] = csrf_from(client, page)
    return token


@contextmanager
def statements_run() -> Iterator[list[str]]:
    """Every SQL statement any engine runs meanwhile, whitespace collapsed (round trips
    counted by the tests of issue 32; BEGIN and COMMIT are not statements here)."""
    from sqlalchemy import event
    from sqlalchemy.engine import Engine

    statements: list[str] = []

    def record(conn, cursor, statement, parameters, context, executemany) -> None:
        statements.append(" ".join(statement.split()))

    event.listen(Engine, "before_cursor_execute", record)
    try:
        yield statements
    finally:
        event.remove(Engine, "before_cursor_execute", record)


def login(client: TestClient, username: str, password: str = PASSWORD, next: str = "/"):
    token = csrf_from(client, "/login")
    return client.post(
        "/login",
        data={"username": username, "password": password, "csrf_token": token, "next": next},
    )


def post_form(client: TestClient, path: str, data: dict | None = None, files=None, page="/"):
    """POST a form the way the browser does: with the CSRF token from a page."""
    token = _form_token(client, page)
    return client.post(path, data={**(data or {}), "csrf_token": token}, files=files)


# --- from test_core_solve.py ----------------------------------------

DATA = Path(__file__).resolve().parent / "data"


# --- from test_cli_science.py ----------------------------------------

HEADING_KEYS = [
    "part",
    "n_positions",
    "samples_per_position",
    "position_means_deg_h",
    "position_sems_deg_h",
    "position_sigmas_deg_h",
    "azimuth_deg",
    "azimuth_sigma_deg",
    "theta_deg",
    "rotate_direction",
    "rotate_deg",
    "then_axis_points",
    "bias_deg_h",
    "bias_sigma_deg_h",
    "amplitude_deg_h",
    "amplitude_sigma_deg_h",
    "closure_residual_deg_h",
    "closure_sigma_deg_h",
    "uncertainty_model",
    "drift_deg_h_per_h",
    "drift_sigma_deg_h_per_h",
    "azimuth_error_deg",
    "azimuth_noise_sigma_deg",
    "warm_up",
]


LATITUDE_KEYS = [
    "part",
    "n_positions",
    "samples_per_position",
    "position_means_deg_h",
    "position_sems_deg_h",
    "position_sigmas_deg_h",
    "latitude_deg",
    "latitude_sigma_deg",
    "earth_rate_deg_h",
    "earth_rate_sigma_deg_h",
    "bias_deg_h",
    "bias_sigma_deg_h",
    "latitude_error_percent",
    "latitude_error_deg",
    "earth_rate_error_percent",
    "closure_residual_deg_h",
    "closure_sigma_deg_h",
    "uncertainty_model",
    "drift_deg_h_per_h",
    "drift_sigma_deg_h_per_h",
    "latitude_noise_sigma_deg",
    "earth_rate_noise_sigma_deg_h",
    "warm_up",
]


# --- from test_api.py ----------------------------------------

API = "/api/v1"


PRACTICE = {
    "title": "Bench 3",
    "station": {"latitude_deg": 39.93, "earth_rate_deg_h": 15.04},
    "heading": {"rotation": "ccw", "start_angle_deg": 0.0},
    "latitude": {"start_angle_deg": 0.0, "step_deg": 90.0},
}


def token_for(client, username, password=PASSWORD) -> dict[str, str]:
    response = client.post(f"{API}/auth/token", data={"username": username, "password": password})
    assert response.status_code == 200, response.text
    body = response.json()
    assert body["token_type"] == "bearer" and body["expires_in"] == 3600
    return {"Authorization": f"Bearer {body['access_token']}"}


def new_api_session(client, auth, body=PRACTICE) -> int:
    response = client.post(f"{API}/sessions", json=body, headers=auth)
    assert response.status_code == 201, response.text
    return response.json()["id"]


# --- from test_lab.py ----------------------------------------


def handout(name: str) -> dict[int, list[float]]:
    with open(DATA / name) as handle:
        rows = list(csv.DictReader(handle))
    return {i: [float(r[f"position_{i}"]) for r in rows] for i in range(1, 5)}


def new_session(client, **fields) -> int:
    data = {"station": "handout", "rotation": "ccw", **fields}
    response = post_form(client, "/lab/sessions", data, page="/lab")
    assert response.status_code == 303, response.text
    return int(response.headers["location"].rsplit("/", 1)[1])


def post_json(client, path: str, body: dict, page: str):
    token = _form_token(client, page)  # json.dumps writes NaN/Infinity as a browser could send
    return client.post(
        path,
        content=json.dumps(body),
        headers={"X-CSRF-Token": token, "Content-Type": "application/json"},
    )


def turn_heading_table(client, session_id: int, position: int, token: str):
    """The heading part's table turned to ``position``, as the lab page's script asks (JSON,
    the page's CSRF token)."""
    return client.post(
        f"/lab/sessions/{session_id}/turn",
        json={"part": "heading", "position": position},
        headers={"X-CSRF-Token": token, "Accept": "application/json"},
    )


def save_manual(client, session_id, part, columns, unit="deg/h"):
    return post_json(
        client,
        f"/lab/sessions/{session_id}/manual",
        {"part": part, "unit": unit, "columns": columns},
        page=f"/lab/sessions/{session_id}",
    )


# --- from test_courses.py ----------------------------------------


def create_course(client, name="Navigation lab") -> int:
    response = post_form(client, "/courses", {"name": name})
    assert response.status_code == 303
    return int(response.headers["location"].rsplit("/", 1)[1])


def import_file(client, course_id, content: bytes, name="roster.csv"):
    return post_form(
        client,
        f"/courses/{course_id}/import",
        files={"roster_file": (name, content, "text/csv")},
        page=f"/courses/{course_id}",
    )


# --- from test_account_takeover.py ----------------------------------------


def section(page: str, element_id: str) -> str:
    """The text of the element with this id (its opening tag up to the next </section>)."""
    start = page.index(f'id="{element_id}"')
    return page[start : page.index("</section>", start)]


# --- from test_review.py ----------------------------------------

HEADING = handout("handout_horizontal.csv")


VERTICAL = handout("handout_vertical.csv")


def build_world(app, teacher) -> dict:
    """Three students in a course of ``teacher`` with an assignment (manual, CSV, simulator)."""
    students = [make_user(f"s{i}", Role.student, name=f"学生{i}") for i in (1, 2, 3)]
    course_id = make_course(teacher, "Nav lab 惯导", tuple(students))
    with write_session() as db:
        assignment = Assignment(
            course_id=course_id,
            title="Find north",
            latitude_deg=39.93,
            earth_rate_deg_h=15.04,
            allowed_methods="manual,csv,simulator",
            true_heading_deg=10.8,
            max_attempts=3,
        )
        db.add(assignment)
        db.flush()
        assignment_id = assignment.id
    return {"course": course_id, "assignment": assignment_id, "app": app}


def set_assignment(world, **fields):
    """Change the world's assignment's columns directly (settings a test needs)."""
    with write_session() as db:
        assignment = db.get(Assignment, world["assignment"])
        for key, value in fields.items():
            setattr(assignment, key, value)
        db.add(assignment)


def browser(world, username):
    client = TestClient(world["app"], follow_redirects=False)
    login(client, username)
    return client


def start(client, world) -> int:
    return new_session(client, assignment_id=str(world["assignment"]))


def do_lab(client, session_id, heading=HEADING, vertical=VERTICAL):
    assert save_manual(client, session_id, "heading", heading).status_code == 200
    assert save_manual(client, session_id, "latitude", vertical).status_code == 200


def submit(client, session_id):
    page = f"/lab/sessions/{session_id}"
    post_form(client, f"{page}/submit", page=page)


def review(client, session_id, **data):
    page = f"/review/sessions/{session_id}"
    return post_form(client, f"{page}/feedback", data, page=page)


# --- from test_route_matrix.py ----------------------------------------

ACCESS = {
    "GET /docs": "public",
    "GET /docs/openapi.json": "public",
    "GET /vendor/plotly-{version}.min.js": "public",
    "GET /login": "public",
    "POST /login": "public",
    "GET /login/sso": "public",  # 404 unless a provider is configured (tests/test_sso.py)
    "GET /login/sso/callback": "public",
    "POST /lang": "public",
    "GET /lti/jwks.json": "public",
    "GET /lti/login": "public",  # the LMS's login initiation (tests/test_lti.py)
    "POST /lti/login": "public",
    "POST /lti/launch": "public",  # authenticated by the id_token, not a cookie
    "GET /lti/state-check": "public",  # reads only this browser's own state cookie
    "GET /lti/continue/{token}": "public",  # a one-time link made by a launch
    "POST /lti/deep-link": "public",  # authenticated by the stored launch's id
    "GET /lti/register": "public",  # needs an administrator's one-time link
    "GET /admin/lti": "admin",
    "POST /admin/lti/platforms": "admin",
    "POST /admin/lti/platforms/{platform_id}/remove": "admin",
    "POST /admin/lti/registration-link": "admin",
    "POST /admin/lti/rotate-key": "admin",
    "POST /courses/{course_id}/lti/sync": "teacher",
    "POST /courses/{course_id}/assignments/{assignment_id}/lti/send": "teacher",
    "GET /lti/links/{link_id}": "teacher",
    "POST /lti/links/{link_id}": "teacher",
    "POST /logout": "user",
    "GET /account/password": "user",
    "POST /account/password": "user",
    "GET /": "user",
    "GET /lab": "user",
    "POST /lab/sessions": "user",
    "GET /account/tokens": "user",
    "GET /explore": "user",
    "GET /explore/data": "user",
    "GET /explore/data.csv": "user",
    "POST /account/tokens": "user",
    "POST /account/tokens/{token_id}/revoke": "token",
    "GET /courses": "teacher-any",
    "POST /courses": "teacher-any",
    "GET /courses/{course_id}": "teacher",
    "POST /courses/{course_id}/rename": "teacher",
    "POST /courses/{course_id}/archive": "teacher",
    "POST /courses/{course_id}/timezone": "teacher",
    "POST /courses/{course_id}/students": "teacher",
    "POST /courses/{course_id}/import": "teacher",
    "POST /courses/{course_id}/students/{student_id}/reset-password": "teacher",
    "POST /courses/{course_id}/students/{student_id}/remove": "teacher",
    "POST /courses/{course_id}/join-code": "teacher",
    "GET /join": "user",
    "POST /join": "user",
    "GET /admin/accounts": "admin",
    "POST /admin/accounts": "admin",
    "POST /admin/accounts/{user_id}/reset-password": "admin",
    "POST /admin/prune": "admin",
    "POST /api/v1/users/{user_id}/reset-password": "teacher",
    "POST /courses/{course_id}/assignments": "teacher",
    "GET /courses/{course_id}/assignments/{assignment_id}": "teacher",
    "POST /courses/{course_id}/assignments/{assignment_id}/settings": "teacher",
    "POST /courses/{course_id}/assignments/{assignment_id}/characterisation": "teacher",
    "GET /courses/{course_id}/assignments/{assignment_id}/export.csv": "teacher",
    "GET /courses/{course_id}/assignments/{assignment_id}/export.xlsx": "teacher",
    "GET /courses/{course_id}/assignments/{assignment_id}/export.zip": "teacher",
    "POST /courses/{course_id}/assignments/{assignment_id}/reports": "teacher",
    "GET /courses/{course_id}/assignments/{assignment_id}/reports/{job_id}": "teacher",
    "GET /courses/{course_id}/assignments/{assignment_id}/reports/{job_id}/download": "teacher",
    "GET /review/sessions/{session_id}/report.pdf": "review",
    "GET /review/sessions/{session_id}": "review",
    "POST /review/sessions/{session_id}/feedback": "review",
    "POST /review/sessions/{session_id}/extension": "review",
    "POST /review/sessions/{session_id}/evidence": "review",
    "GET /review/archives": "teacher-any",
    "POST /review/archives": "teacher-any",
    "POST /review/archives/{archive_id}/delete": "teacher",
    "GET /courses/{course_id}/assignments/{assignment_id}/board": "teacher",
    "GET /courses/{course_id}/assignments/{assignment_id}/board.json": "teacher",
    "POST /courses/{course_id}/assignments/{assignment_id}/board/snapshots": "teacher",
    "GET /courses/{course_id}/assignments/{assignment_id}/board/snapshots/{snapshot_id}": "teacher",
    "POST /courses/{course_id}/assignments/{assignment_id}/release": "teacher",
    "GET /lab/sessions/{session_id}": "owner",
    "POST /lab/sessions/{session_id}/manual": "owner",
    "POST /lab/sessions/{session_id}/csv/preview": "owner",
    "POST /lab/sessions/{session_id}/csv/binary": "owner",
    "POST /lab/sessions/{session_id}/csv": "owner",
    "POST /lab/sessions/{session_id}/turn": "owner",
    "POST /lab/sessions/{session_id}/plane": "owner",
    "POST /lab/sessions/{session_id}/order": "owner",
    "POST /lab/sessions/{session_id}/wait": "owner",
    "POST /lab/sessions/{session_id}/trim": "owner",
    "GET /lab/sessions/{session_id}/state": "owner",
    "POST /lab/sessions/{session_id}/leave": "owner",
    "POST /lab/join-group": "user",
    "GET /lab/sessions/{session_id}/grid.json": "owner",
    "GET /lab/sessions/{session_id}/results.json": "owner",
    "POST /lab/sessions/{session_id}/submit": "owner",
    "GET /lab/sessions/{session_id}/export.csv": "owner",
    "GET /lab/sessions/{session_id}/export.json": "owner",
    "GET /lab/sessions/{session_id}/report.pdf": "owner",
    "POST /lab/sessions/{session_id}/discussion": "owner",
    "WS /lab/sessions/{session_id}/stream": "owner",
    "POST /api/v1/auth/token": "public",
    "GET /api/v1/me": "user",
    "GET /api/v1/sessions": "user",
    "POST /api/v1/sessions": "user",
    "GET /api/v1/sessions/{session_id}": "owner",
    "PUT /api/v1/sessions/{session_id}/{part}/positions/{position}": "owner",
    "POST /api/v1/sessions/{session_id}/{part}/positions/{position}/samples": "owner",
    "GET /api/v1/sessions/{session_id}/results": "owner",
    "GET /api/v1/sessions/{session_id}/plan": "owner",
    "GET /api/v1/sessions/{session_id}/report.pdf": "owner",
    "POST /api/v1/sessions/{session_id}/submit": "owner",
    "PUT /api/v1/sessions/{session_id}/{part}/positions/{position}/trim": "owner",
    "GET /api/v1/courses": "teacher-any",
    "GET /api/v1/assignments/{assignment_id}/submissions": "teacher",
    "GET /api/v1/assignments/{assignment_id}/accuracy": "teacher",
    "GET /api/v1/assignments/{assignment_id}/board": "teacher",
    "GET /api/v1/assignments/{assignment_id}/export.csv": "teacher",
    "GET /api/v1/assignments/{assignment_id}/export.xlsx": "teacher",
    "GET /api/v1/archives": "teacher-any",
    "POST /api/v1/archives": "teacher-any",
    "DELETE /api/v1/archives/{archive_id}": "teacher",
}


def concrete(route: str, ids: dict) -> tuple[str, str]:
    method, path = route.split(" ", 1)
    if "{version}" in path:
        from app.main import PLOTLY_URL

        return method, PLOTLY_URL
    return method, path.format(**ids)


JSON_BODIES = {  # routes of the lab page that take JSON (fetch) rather than forms
    "/manual": {"part": "heading", "columns": {"1": [1.0] * 10}},
    "/csv": {"part": "heading", "text": "position_1\n1\n"},
    "/csv/preview": {"part": "heading", "text": "position_1\n1\n"},
    "/turn": {"part": "heading", "position": 2},
    "/plane": {"dial_deg": -12.5},
}


RAW_BODIES = {  # routes of the lab page that take a file's bytes as they are
    "/csv/binary": b"PK\x03\x04 an Excel workbook's bytes",
}


def request(client, method, path, headers=None):
    headers = dict(headers or {})
    if method in ("POST", "PUT"):
        if path.startswith("/api/"):
            return client.request(method, path, json={"samples": [1.0] * 10}, headers=headers)
        page = "/login" if "gyrolab_session" not in client.cookies else "/lab"
        token = csrf_from(client, page)
        raw = next((s for s in RAW_BODIES if path.startswith("/lab/") and path.endswith(s)), None)
        if raw:
            return client.request(
                method,
                path,
                content=RAW_BODIES[raw],
                headers={
                    **headers,
                    "X-CSRF-Token": token,
                    "Content-Type": "application/octet-stream",
                    "Accept": "application/json",
                },
            )
        suffix = next(
            (s for s in JSON_BODIES if path.startswith("/lab/") and path.endswith(s)), None
        )
        if suffix:
            return client.request(
                method, path, json=JSON_BODIES[suffix], headers={**headers, "X-CSRF-Token": token}
            )
        return client.request(method, path, data={"csrf_token": token}, headers=headers)
    return client.request(method, path, headers=headers)


def credentials_from(page: str) -> dict[str, str]:
    href = re.search(r'href="data:text/csv;charset=utf-8,([^"]+)"', page).group(1)
    text = unquote(href.replace("&amp;", "&")).lstrip("\ufeff")
    rows = list(csv.reader(io.StringIO(text)))  # columns named in the page's language
    return {username: password for username, _name, password in rows[1:]}


# --- forms as a browser reads them (issue 34) --------------------------


@dataclass
class FormState:
    """What a person sees in a form: each field's value (the checked radio, the selected
    option, a textarea's text; checkboxes as a list of the checked ones), the refused
    fields (``aria-invalid``) in page order, the one with the focus, and the messages
    beside fields by the field's name."""

    values: dict = field(default_factory=dict)
    refused: list = field(default_factory=list)
    autofocus: str | None = None
    errors: dict = field(default_factory=dict)
    text: str = ""


def form_state(page: str, form_id: str) -> FormState:
    """The state of the form with id ``form_id`` in the HTML ``page``."""
    from html.parser import HTMLParser

    state = FormState()

    class Reader(HTMLParser):
        depth = 0  # > 0 inside the form
        select: str | None = None
        textarea: str | None = None
        error: str | None = None

        def handle_starttag(self, tag, attrs):
            a = dict(attrs)
            if tag == "form" and a.get("id") == form_id:
                self.depth = 1
                return
            if not self.depth:
                return
            if tag == "form":
                self.depth += 1
            name = a.get("name")
            if name and a.get("aria-invalid") == "true":
                state.refused.append(name)
            if name and "autofocus" in a and state.autofocus is None:
                state.autofocus = name
            if tag == "input" and name and a.get("type") != "hidden":
                if a.get("type") == "checkbox":
                    state.values.setdefault(name, [])
                    if "checked" in a:
                        state.values[name].append(a.get("value"))
                elif a.get("type") == "radio":
                    if "checked" in a:
                        state.values[name] = a.get("value")
                else:
                    state.values[name] = a.get("value", "")
            elif tag == "select":
                self.select = name
            elif tag == "option" and self.select and "selected" in a:
                state.values[self.select] = a.get("value")
            elif tag == "textarea":
                self.textarea = name
                state.values[name] = ""
            elif "field-error" in (a.get("class") or "").split():
                self.error = (a.get("id") or "").removeprefix("error-")
                state.errors[self.error] = ""

        def handle_endtag(self, tag):
            if not self.depth:
                return
            if tag == "form":
                self.depth -= 1
            elif tag == "select":
                self.select = None
            elif tag == "textarea":
                self.textarea = None
            elif tag == "span" and self.error:
                self.error = None

        def handle_data(self, data):
            if not self.depth:
                return
            state.text += data
            if self.textarea:
                state.values[self.textarea] += data
            if self.error:
                state.errors[self.error] += data

    Reader(convert_charrefs=True).feed(page)
    return state
