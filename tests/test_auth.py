"""Login, logout, sessions, throttling, password changes and CSRF."""

from __future__ import annotations

from datetime import timedelta

from sqlmodel import select

from app.accounts.security import verify_password
from app.config import get_settings
from app.db import read_session, write_session
from app.models import AuthSession, Role, User, utcnow
from app.routes import iter_routes
from app.web.render import SESSION_COOKIE
from tests.factories import PASSWORD, csrf_from, login, make_user, post_form


def test_login_page_renders_with_csrf_cookie(client):
    response = client.get("/login")
    assert response.status_code == 200
    assert "gyrolab_csrf" in response.cookies
    assert 'name="csrf_token"' in response.text


def test_anonymous_is_sent_to_login(client):
    response = client.get("/")
    assert response.status_code == 303
    assert response.headers["location"] == "/login?next=/"


def test_login_and_logout(client, teacher):
    response = login(client, "teacher1")
    assert response.status_code == 303 and response.headers["location"] == "/"
    cookie = client.cookies[SESSION_COOKIE]
    page = client.get("/")
    assert page.status_code == 200 and "Teacher One" in page.text
    response = post_form(client, "/logout")
    assert response.headers["location"] == "/login"
    # Replaying the old cookie after logout gets the login page, not the dashboard.
    client.cookies.set(SESSION_COOKIE, cookie)
    assert client.get("/").headers["location"].startswith("/login")


def test_username_is_case_insensitive(client, teacher):
    assert login(client, "  TEACHER1 ").status_code == 303


def test_a_student_number_typed_in_full_width_forms_is_the_same_username(client):
    """A Chinese input method in full-width mode types "２０２３０１０１０１": the account
    made from it is "2023010101", and either spelling logs in."""
    make_user("２０２３０１０１０１")
    with read_session() as db:
        assert db.exec(select(User.username)).all() == ["2023010101"]
    assert login(client, "2023010101").status_code == 303
    client.cookies.clear()
    assert login(client, "２０２３０１０１０１").status_code == 303


def test_session_cookie_flags(client, teacher):
    response = login(client, "teacher1")
    header = response.headers["set-cookie"].lower()
    assert "httponly" in header and "samesite=lax" in header
    assert "secure" not in header  # plain http in tests; https sets Secure


def test_session_token_is_stored_hashed(client, teacher):
    login(client, "teacher1")
    token = client.cookies[SESSION_COOKIE]
    with read_session() as db:
        stored = db.exec(select(AuthSession.token_hash)).all()
    assert token not in stored and len(stored) == 1


def test_same_message_for_unknown_user_and_wrong_password(client, teacher):
    unknown = login(client, "nobody", "whatever-123")
    wrong = login(client, "teacher1", "wrong-password")
    assert unknown.status_code == wrong.status_code == 401
    assert "Wrong username or password." in unknown.text
    assert "Wrong username or password." in wrong.text


def age_failures(seconds: float) -> None:
    """Move every recorded log-in failure ``seconds`` into the past."""
    from app.models import LoginFailure

    with write_session() as db:
        for failure in db.exec(select(LoginFailure)).all():
            failure.at = failure.at - timedelta(seconds=seconds)
            db.add(failure)


def fail(client, username: str, times: int) -> None:
    """Wrong passwords one after another, each after its growing delay has passed."""
    for i in range(times):
        assert login(client, username, f"wrong-{i}").status_code == 401
        age_failures(20)


def test_wrong_passwords_slow_down_then_pause(client, teacher):
    assert [login(client, "teacher1", f"wrong-{i}").status_code for i in range(2)] == [401, 401]
    for delay in (2, 4, 8):  # the same account from the same address: growing delays
        response = login(client, "teacher1", "wrong-again")
        wait = int(response.headers["Retry-After"])
        # the delay runs from the failed attempt; a slow machine may have used a second
        assert response.status_code == 429 and delay - 1 <= wait <= delay
        assert f"wait {wait} seconds" in response.text
        age_failures(delay + 0.5)
        assert login(client, "teacher1", "wrong-again").status_code == 401
    response = login(client, "teacher1")  # five failures: even the right password waits
    assert response.status_code == 429
    assert "Too many failed log-in attempts" in response.text


def test_throttle_is_stored_in_the_database(app, teacher):
    """A new app instance (a restart, another worker) still sees the failures."""
    from fastapi.testclient import TestClient

    from app.main import create_app

    with TestClient(app, follow_redirects=False) as first:
        fail(first, "teacher1", 5)
    with TestClient(create_app(migrate_on_start=False), follow_redirects=False) as second:
        assert login(second, "teacher1").status_code == 429


def test_throttle_window_expires(client, teacher):
    fail(client, "teacher1", 5)
    assert login(client, "teacher1").status_code == 429
    age_failures(get_settings().login_window_minutes * 60 + 1)
    assert login(client, "teacher1").status_code == 303


def test_guesses_from_elsewhere_never_lock_out_the_user(app, student):
    """Ten guesses at one account from anywhere stop strangers for the window; the browser
    the student logged in with before still gets in (a signed device cookie)."""
    from fastapi.testclient import TestClient

    own = TestClient(app, follow_redirects=False)
    assert login(own, "student1").status_code == 303
    post_form(own, "/logout")
    for n in range(5):  # two guesses from each of five addresses
        with TestClient(app, follow_redirects=False, client=(f"203.0.113.{n}", 1)) as attacker:
            assert login(attacker, "student1", "guess-a").status_code == 401
            assert login(attacker, "student1", "guess-b").status_code == 401
    with TestClient(app, follow_redirects=False, client=("198.51.100.7", 1)) as stranger:
        assert login(stranger, "student1").status_code == 429  # brute force stays slow
        assert login(stranger, "student1", "guess-c").status_code == 429
    assert login(own, "student1").status_code == 303


def test_a_class_behind_one_address_is_not_locked_out(app, teacher):
    """35 wrong passwords from one address (a lab behind NAT, 18 students mistyping twice)
    do not lock out the teacher or anyone else there."""
    from fastapi.testclient import TestClient

    for n in range(18):
        make_user(f"s{n}")
        with TestClient(app, follow_redirects=False) as browser:
            for attempt in range(2 if n < 17 else 1):
                assert login(browser, f"s{n}", f"typo-{attempt}").status_code == 401
    with TestClient(app, follow_redirects=False) as browser:
        assert login(browser, "teacher1").status_code == 303
    with TestClient(app, follow_redirects=False) as browser:
        assert login(browser, "s17").status_code == 303


def test_password_hashing_is_bounded(client, teacher, monkeypatch):
    """At most login_hash_slots hashes at once: a flood of log-ins waits briefly, then
    answers 503, and is not charged as a failure."""
    from app.accounts import security
    from app.models import LoginFailure

    monkeypatch.setattr(security, "HASH_WAIT_SECONDS", 0.05)
    slots = security._hash_slots(get_settings().login_hash_slots)
    for _ in range(get_settings().login_hash_slots):
        assert slots.acquire(timeout=1)
    try:
        busy = login(client, "teacher1")
        assert busy.status_code == 503 and busy.headers["Retry-After"] == "1"
        assert "busy" in busy.text
        with write_session() as db:
            assert db.exec(select(LoginFailure)).all() == []
    finally:
        for _ in range(get_settings().login_hash_slots):
            slots.release()
    assert login(client, "teacher1").status_code == 303


def test_a_log_in_gives_its_work_place_back_while_it_hashes(app, teacher, monkeypatch):
    """argon2id runs outside the interpreter lock, bounded by the hash slots: the request's
    place (web.admission) is another request's meanwhile, given back before the hash."""
    from app.accounts import security
    from app.db import give_way_hook

    events: list[str] = []
    hash_check = security.check_password
    monkeypatch.setattr(
        security,
        "check_password",
        lambda *args: events.append("hash") or hash_check(*args),
    )
    token = give_way_hook.set(lambda: events.append("gave way"))
    try:
        with write_session() as db:
            outcome = security.log_in(db, "teacher1", PASSWORD, "127.0.0.1", get_settings())
    finally:
        give_way_hook.reset(token)
    assert outcome.user is not None and "gave way" in events[: events.index("hash")]


def test_idle_session_expires(client, teacher):
    login(client, "teacher1")
    with write_session() as db:
        record = db.exec(select(AuthSession)).one()
        record.last_seen_at = utcnow() - timedelta(minutes=get_settings().session_idle_minutes + 1)
        db.add(record)
    assert client.get("/").status_code == 303


def test_absolute_lifetime_expires(client, teacher):
    login(client, "teacher1")
    with write_session() as db:
        record = db.exec(select(AuthSession)).one()
        record.expires_at = utcnow() - timedelta(seconds=1)
        db.add(record)
    assert client.get("/").status_code == 303


def test_open_redirect_is_refused(client, teacher):
    response = login(client, "teacher1", next="//evil.example/")
    assert response.headers["location"] == "/"
    response = post_form(client, "/logout")
    response = login(client, "teacher1", next="https://evil.example/")
    assert response.headers["location"] == "/"


def test_post_without_csrf_token_is_refused(client, teacher):
    login(client, "teacher1")
    response = client.post("/courses", data={"name": "Sneaky"})
    assert response.status_code == 403
    response = client.post("/courses", data={"name": "Sneaky", "csrf_token": "forged"})
    assert response.status_code == 403


def test_login_without_csrf_is_refused(client, teacher):
    client.get("/login")
    response = client.post("/login", data={"username": "teacher1", "password": PASSWORD})
    assert response.status_code == 403


def test_csrf_header_is_accepted(client, teacher):
    login(client, "teacher1")
    token = csrf_from(client, "/")
    response = client.post("/courses", data={"name": "Via header"}, headers={"X-CSRF-Token": token})
    assert response.status_code == 303


def test_every_state_changing_route_checks_csrf(app):
    from fastapi.routing import APIRoute

    from app.accounts.deps import csrf_protect

    unsafe = [
        route
        for route in iter_routes(app.routes)
        if isinstance(route, APIRoute)
        and route.methods - {"GET", "HEAD", "OPTIONS"}
        and not route.path.startswith("/api/")
    ]
    assert unsafe, "expected some form routes"
    for route in unsafe:
        if route.path in LTI_PROTOCOL_POSTS:
            continue
        calls = {dep.call for dep in route.dependant.dependencies}
        assert csrf_protect in calls, f"{route.path} lacks CSRF protection"


# Posts of the LTI protocol, made by the LMS's auto-submitting forms: none acts on a
# cookie's authority (tests/test_lti.py tests what protects each instead).
LTI_PROTOCOL_POSTS = {
    "/lti/login": "changes nothing but a state cookie and a nonce",
    "/lti/launch": "the platform-signed id_token, this browser's state cookie, a one-time nonce",
    "/lti/deep-link": "the id of a stored deep-linking launch, used once",
}


def test_forced_password_change(client):
    make_user("newbie", Role.student, must_change=True)
    response = login(client, "newbie")
    assert response.headers["location"] == "/account/password"
    assert client.get("/").headers["location"] == "/account/password"
    page = client.get("/account/password")
    assert "initial password" in page.text
    response = post_form(
        client,
        "/account/password",
        {
            "current_password": PASSWORD,
            "new_password": "my-own-secret-9",
            "confirm_password": "my-own-secret-9",
        },
        page="/account/password",
    )
    assert response.status_code == 303
    assert client.get("/").status_code == 200
    with read_session() as db:
        user = db.exec(select(User).where(User.username == "newbie")).one()
    assert not user.must_change_password
    assert verify_password("my-own-secret-9", user.password_hash)


def test_password_change_revokes_other_sessions(app, teacher):
    from fastapi.testclient import TestClient

    with (
        TestClient(app, follow_redirects=False) as laptop,
        TestClient(app, follow_redirects=False) as phone,
    ):
        login(laptop, "teacher1")
        login(phone, "teacher1")
        response = post_form(
            laptop,
            "/account/password",
            {
                "current_password": PASSWORD,
                "new_password": "another-secret-7",
                "confirm_password": "another-secret-7",
            },
            page="/account/password",
        )
        assert response.status_code == 303
        assert laptop.get("/").status_code == 200
        assert phone.get("/").status_code == 303


def test_password_rules(client, teacher):
    login(client, "teacher1")
    cases = [
        (
            {
                "current_password": "nope",
                "new_password": "abcdefgh1",
                "confirm_password": "abcdefgh1",
            },
            "current password is wrong",
        ),
        (
            {"current_password": PASSWORD, "new_password": "abcdefgh1", "confirm_password": "x"},
            "differ",
        ),
        (
            {"current_password": PASSWORD, "new_password": "short", "confirm_password": "short"},
            "at least 8",
        ),
        (
            {
                "current_password": PASSWORD,
                "new_password": "teacher1",
                "confirm_password": "teacher1",
            },
            "must not be your username",
        ),
    ]
    for data, message in cases:
        response = post_form(client, "/account/password", data, page="/account/password")
        assert response.status_code == 400
        assert message in response.text


def test_successful_log_ins_leave_no_failure_and_failures_charge_both(client, teacher):
    """The attempt is charged before the hash (parallel guesses cannot pass a limit) and
    uncharged on success; the address only for wrong passwords, so a class logging in at
    once behind one address is never throttled by its own log-ins."""
    from app.db import read_session
    from app.models import LoginFailure

    def failures() -> list[str]:
        with read_session() as db:
            return sorted(f.scope for f in db.exec(select(LoginFailure)).all())

    assert login(client, "teacher1").status_code == 303
    assert failures() == []
    client.cookies.clear()
    assert login(client, "Teacher1", "wrong-password").status_code == 401
    assert failures() == ["account", "address", "pair"]
    token = client.post("/api/v1/auth/token", data={"username": "teacher1", "password": PASSWORD})
    assert token.status_code == 200
    # the pair's failures go; the account's stay (another's guesses are not forgiven)
    assert failures() == ["account", "address"]


def test_pre_login_csrf_cookie_is_host_only_over_https(app, teacher):
    """A sibling subdomain cannot plant the log-in form's CSRF cookie: over https it is a
    __Host- cookie, and the plain-named cookie it could plant is ignored."""
    from fastapi.testclient import TestClient

    with TestClient(app, base_url="https://testserver", follow_redirects=False) as secure:
        page = secure.get("/login")
        header = page.headers["set-cookie"]
        assert header.startswith("__Host-gyrolab_csrf=")
        assert "secure" in header.lower() and "path=/" in header.lower()
        assert "domain" not in header.lower()
        token = csrf_from(secure, "/login")
        planted = "planted-token-123456789"
        secure.cookies.clear()
        secure.cookies.set("gyrolab_csrf", planted)
        refused = secure.post(
            "/login",
            data={"username": "teacher1", "password": PASSWORD, "csrf_token": planted},
        )
        assert refused.status_code == 403
        secure.cookies.clear()
        secure.cookies.set("__Host-gyrolab_csrf", token)
        accepted = secure.post(
            "/login", data={"username": "teacher1", "password": PASSWORD, "csrf_token": token}
        )
        assert accepted.status_code == 303


def test_production_passwords_use_owasp_argon2id_parameters(monkeypatch):
    """The suite hashes with argon2's cheapest parameters (conftest); the app's own are
    OWASP's minimum for argon2id in its least-memory setting: m=7 MiB, t=5, p=1.  A hash
    made with the earlier setting (m=19 MiB, t=2) still verifies."""
    from argon2 import PasswordHasher, Type

    from app.accounts import security
    from tests.conftest import PRODUCTION_ARGON2

    assert PRODUCTION_ARGON2 == (7 * 1024, 5, 1)
    for name, value in zip(
        ("ARGON2_MEMORY_KIB", "ARGON2_TIME_COST", "ARGON2_PARALLELISM"),
        PRODUCTION_ARGON2,
        strict=True,
    ):
        monkeypatch.setattr(security, name, value)
    security.password_hasher.cache_clear()
    earlier = PasswordHasher(time_cost=2, memory_cost=19 * 1024, parallelism=1, type=Type.ID)
    try:
        digest = security.hash_password("correct-horse-42")
        assert digest.startswith("$argon2id$v=19$m=7168,t=5,p=1$")
        assert security.verify_password("correct-horse-42", digest)
        assert not security.verify_password("wrong-horse-42", digest)
        stored = earlier.hash("correct-horse-42")
        assert stored.startswith("$argon2id$v=19$m=19456,t=2,p=1$")
        assert security.verify_password("correct-horse-42", stored)
        assert not security.verify_password("wrong-horse-42", stored)
    finally:
        monkeypatch.undo()
        security.password_hasher.cache_clear()


def test_a_log_in_costs_few_round_trips(client, teacher, backend):
    """A class logs in at once (bench/README.md, issue 32): on PostgreSQL each statement
    is a round trip and ≈ 90 µs of the worker's interpreter.  The throttle's locks are one
    statement, its counts one, and a success uncharges its attempt and writes the session
    row in one transaction."""
    from tests.factories import statements_run

    token = csrf_from(client, "/login")
    form = {"username": "teacher1", "password": PASSWORD, "csrf_token": token}
    with statements_run() as succeeded:
        assert client.post("/login", data=form).status_code == 303
    client.cookies.pop(SESSION_COOKIE)
    with statements_run() as failed:
        assert client.post("/login", data={**form, "password": "wrong-pass"}).status_code == 401
    locks = [s for s in succeeded if "pg_advisory_xact_lock(" in s]
    reads = [s for s in succeeded if s.startswith("SELECT login_failure")]
    assert len(locks) == (1 if backend == "postgresql" else 0), succeeded
    assert len(reads) == 1, succeeded
    deletes = [s for s in succeeded if s.startswith("DELETE FROM login_failure")]
    assert len(deletes) == 1, succeeded
    if backend == "postgresql":  # each write transaction opens with its try of the write lock
        assert sum("pg_try_advisory_xact_lock" in s for s in succeeded) == 2, succeeded
    limit = {"sqlite": 6, "postgresql": 8}[backend]  # was 9 and 14; BEGIN and COMMIT not seen
    assert len(succeeded) <= limit, succeeded
    assert len(failed) <= limit, failed


def test_a_hash_of_other_parameters_is_replaced_at_the_next_log_in(client, teacher):
    """Stored hashes converge on the app's parameters (so every account costs an attacker,
    and a check, the same): the first successful log-in re-hashes; a wrong password not."""
    from argon2 import PasswordHasher, Type

    older = PasswordHasher(time_cost=2, memory_cost=16, parallelism=1, type=Type.ID)
    with write_session() as db:
        user = db.exec(select(User).where(User.username == "teacher1")).one()
        user.password_hash = older.hash(PASSWORD)
        db.add(user)

    def stored() -> str:
        with read_session() as db:
            return db.exec(select(User).where(User.username == "teacher1")).one().password_hash

    assert login(client, "teacher1", "wrong-password").status_code == 401
    assert stored().startswith("$argon2id$v=19$m=16,t=2,p=1$")
    assert login(client, "teacher1").status_code == 303
    assert stored().startswith("$argon2id$v=19$m=8,t=1,p=1$")
    assert verify_password(PASSWORD, stored())
    client.cookies.clear()
    assert login(client, "teacher1").status_code == 303


def test_a_request_finds_its_caller_in_one_statement(client, student):
    """The log-in session and its user come in one joined statement (was two: every
    request of a class pays for each round trip)."""
    from tests.factories import statements_run

    assert login(client, "student1").status_code == 303
    with statements_run() as statements:
        assert client.get("/lab").status_code == 200
    logins = [s for s in statements if "FROM auth_session" in s]
    assert len(logins) == 1 and "JOIN" in logins[0], statements
    by_id = [
        s for s in statements if s.startswith("SELECT") and "FROM user WHERE" in s.replace('"', "")
    ]
    assert by_id == [], statements
