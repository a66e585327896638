"""GyroLab as an LTI 1.3 tool against a real platform on loopback (tests/lti_platform.py,
built on lti1p3platform): deep linking, launches, roster sync, grade passback with
retries, dynamic registration, key rotation -- and the launch's security checks, each
refused with a clear page and nobody logged in."""

from __future__ import annotations

import re
import time
from collections.abc import Iterator
from dataclasses import dataclass
from urllib.parse import urlsplit

import jwt
import pytest
from sqlmodel import select

from app.db import read_session, write_session
from app.lti import grades, keys
from app.lti.platforms import PlatformFields, add_platform
from app.models import (
    Enrollment,
    ExternalIdentity,
    LtiContext,
    LtiGradePost,
    LtiPlatform,
    Role,
    User,
)
from tests.factories import CSRF_RE, HEADING, VERTICAL, make_user, post_form, without_tokens
from tests.lti_platform import (
    CLIENT_ID,
    Browser,
    PlatformState,
    bound_socket,
    create_platform_app,
    serving,
    url_of,
)

pytestmark = pytest.mark.slow  # a real LMS and GyroLab served on loopback

REFUSED = "GyroLab could not open this launch"
protocol_only = pytest.mark.one_backend


@dataclass
class Lti:
    tool: str  # GyroLab's address
    platform: PlatformState

    def browser(self, **headers) -> Browser:
        return Browser(headers={"Accept-Language": "en", **headers})


@pytest.fixture
def lti(app) -> Iterator[Lti]:
    tool_socket, platform_socket = bound_socket(), bound_socket()
    tool = url_of(tool_socket)
    state = PlatformState(url=url_of(platform_socket), tool_url=tool)
    fields = state.platform_fields()
    with write_session() as db:
        add_platform(
            db,
            PlatformFields(
                **{k: v for k, v in fields.items() if k != "deployment_ids"},
                deployment_ids=[fields["deployment_ids"]],
            ),
        )
    with serving(app, tool_socket, create_platform_app(state), platform_socket):
        yield Lti(tool, state)


def deep_link_new_assignment(lti: Lti, title="Find north 寻北") -> Browser:
    """The teacher adds GyroLab from the LMS's "add activity" and creates an assignment."""
    teacher = lti.browser()
    picker = teacher.launch(lti.platform.url, user="teacher-1", kind="deep")
    assert picker.status_code == 200, picker.text[:300]
    assert "Add a GyroLab activity" in picker.text
    back = teacher.client.post(
        f"{lti.tool}/lti/deep-link",
        data={
            "launch_id": _launch_id(picker.text),
            "new": "1",
            "title": title,
            "latitude_deg": "34.25",
            "max_points": "50",
        },
    )
    assert back.status_code == 200 and 'name="JWT"' in back.text, back.text[-1500:]
    csp = back.headers["content-security-policy"]
    assert f"form-action 'self' {lti.platform.url}" in csp  # the auto-post may leave
    done = teacher.submit_auto_form(back)
    assert done.status_code == 200 and "added 1" in done.text, done.text
    return teacher


def _launch_id(page: str) -> str:
    return page.split('name="launch_id" value="', 1)[1].split('"', 1)[0]


def cookie_names(browser: Browser) -> set[str]:
    return {cookie.name for cookie in browser.client.cookies.jar}


# --- the whole round trip -----------------------------------------------------------------------


def test_deep_link_launch_roster_session_and_grade_reach_the_platform(lti):
    deep_link_new_assignment(lti)
    link_id, item = next(iter(lti.platform.links.items()))
    assert item["title"] == "Find north 寻北"
    lineitem = lti.platform.lineitems[item["lineitem"]]
    assert lineitem["scoreMaximum"] == 50 and lineitem["resourceId"].startswith("gyrolab-")

    teacher = lti.browser()
    dashboard = teacher.launch(lti.platform.url, user="teacher-1", link=link_id)
    assert dashboard.status_code == 200
    assert urlsplit(str(dashboard.url)).path.endswith(
        f"/assignments/{item['custom']['gyrolab_assignment']}"
    )
    assert "Grades in the learning platform" in dashboard.text

    # the roster came from NRPS after the teacher's launch: three learners, not the observer
    # and not the member the LMS lists as inactive
    wait_for_roster_sync()
    with read_session() as db:
        enrolled = set(
            db.exec(select(User.display_name).join(Enrollment, Enrollment.student_id == User.id))
        )
        assert enrolled == {"Li Wei 李伟", "Zhao Min", "Sun Li"}
        student = db.exec(
            select(User)
            .join(ExternalIdentity, ExternalIdentity.user_id == User.id)
            .where(ExternalIdentity.subject == "student-1")
        ).one()
        assert student.role == Role.student and student.email == "liwei@uni.example"

    # a student's first launch lands in their own session, with no GyroLab password
    learner = lti.browser()
    lab = learner.launch(lti.platform.url, user="student-1", link=link_id)
    assert lab.status_code == 200 and "/lab/sessions/" in str(lab.url)
    session_id = int(urlsplit(str(lab.url)).path.rsplit("/", 1)[1])
    assert learner.get(f"{lti.tool}/account/password").status_code == 200
    again = lti.browser().launch(lti.platform.url, user="student-1", link=link_id)
    assert str(again.url) == str(lab.url)  # the same session, every launch

    _record_and_submit(learner, lti.tool, session_id)
    released = _release(teacher, lti.tool, session_id, points="42", feedback="Good work 很好")
    assert released.status_code == 200
    scores = arrived(lti.platform.scores, 1)
    assert scores[0]["userId"] == "student-1" and scores[0]["scoreGiven"] == 42
    assert scores[0]["scoreMaximum"] == 50 and scores[0]["comment"] == "Good work 很好"
    assert scores[0]["gradingProgress"] == "FullyGraded"
    assert scores[0]["lineitem"] == item["lineitem"]
    wait_until_sent(1)  # the platform answers before GyroLab records the acknowledgement
    assert "1 grades received by the learning platform, 0 waiting" in without_tokens(
        teacher.get(str(dashboard.url)).text
    )


def test_a_release_by_any_caller_queues_the_lms_grade(lti):
    """release() owns all its effects: called as a script or the command line would call it
    (no desk page, no background task), the grade still reaches the LMS."""
    from app.lab.attempts import latest_attempt
    from app.models import Attempt, LabSession
    from app.review import grading

    deep_link_new_assignment(lti)
    link_id = next(iter(lti.platform.links))
    lti.browser().launch(lti.platform.url, user="teacher-1", link=link_id)  # the roster
    learner = lti.browser()
    lab = learner.launch(lti.platform.url, user="student-1", link=link_id)
    session_id = int(urlsplit(str(lab.url)).path.rsplit("/", 1)[1])
    _record_and_submit(learner, lti.tool, session_id)
    with write_session() as db:
        session = db.get(LabSession, session_id)
        attempt: Attempt = latest_attempt(db, session_id)
        attempt.points = 37.0
        assert grading.release(db, session, attempt) == 1
    with read_session() as db:
        assert [p.score for p in db.exec(select(LtiGradePost))] == [37.0]
    assert grades.send_due() == {"sent": 1, "failed": 0}
    assert lti.platform.scores[-1]["scoreGiven"] == 37 and len(lti.platform.scores) == 1


def arrived(scores: list, count: int, seconds: float = 10) -> list:
    """The platform's scores once ``count`` have come (the sender works after the release)."""
    deadline = time.monotonic() + seconds
    while len(scores) < count and time.monotonic() < deadline:
        time.sleep(0.05)
    return scores


def wait_for_roster_sync(seconds: float = 10) -> None:
    """The roster is fetched in a task after the launch's response, so a client that has
    already loaded the next page may be ahead of it; wait until the sync has been recorded."""
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        with read_session() as db:
            contexts = db.exec(select(LtiContext)).all()
        if contexts and all(c.roster_synced_at or c.roster_problem for c in contexts):
            assert not any(c.roster_problem for c in contexts), contexts
            return
        time.sleep(0.05)
    raise AssertionError(f"the roster was not synced within {seconds} s")


def wait_until_sent(count: int, seconds: float = 10) -> None:
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        with read_session() as db:
            sent = db.exec(select(LtiGradePost).where(LtiGradePost.status == "sent")).all()
        if len(sent) >= count:
            return
        time.sleep(0.05)
    raise AssertionError(f"{count} grade posts not acknowledged in {seconds} s")


def csrf_of(browser: Browser, url: str) -> str:
    return CSRF_RE.search(browser.get(url).text).group(1)


def _record_and_submit(browser: Browser, tool: str, session_id: int) -> None:
    page = f"{tool}/lab/sessions/{session_id}"
    csrf = csrf_of(browser, page)
    for part, columns in (("heading", HEADING), ("latitude", VERTICAL)):
        saved = browser.client.post(
            f"{page}/manual",
            json={
                "part": part,
                "columns": {str(k): v for k, v in columns.items()},
                "unit": "deg/h",
            },
            headers={"X-CSRF-Token": csrf},
        )
        assert saved.status_code == 200, saved.text[:300]
    submitted = browser.client.post(f"{page}/submit", data={"csrf_token": csrf})
    assert submitted.status_code == 200


def _release(teacher: Browser, tool: str, session_id: int, **review):
    page = f"{tool}/review/sessions/{session_id}"
    csrf = csrf_of(teacher, page)
    return teacher.client.post(
        f"{page}/feedback", data={"csrf_token": csrf, "action": "release", **review}
    )


# --- the launch's security checks: each refused with a page, nobody logged in ------------------


def refused_launch(lti: Lti, browser: Browser | None = None, **start) -> None:
    browser = browser or lti.browser()
    page = browser.launch(lti.platform.url, **{"user": "teacher-1", "kind": "deep", **start})
    assert page.status_code in (400, 401), page.text[:300]
    assert REFUSED in page.text
    assert "gyrolab_session" not in cookie_names(browser)
    with read_session() as db:
        assert db.exec(select(ExternalIdentity)).first() is None  # no account was made


def tamper(lti: Lti, edit) -> None:
    def edited(claims: dict) -> dict:
        edit(claims)
        return claims

    lti.platform.tamper = edited


@protocol_only
def test_a_forged_signature_is_refused(lti):
    lti.platform.forge = True
    refused_launch(lti)


@protocol_only
def test_an_expired_id_token_is_refused(lti):
    lti.platform.expires_in = -30
    refused_launch(lti)


@protocol_only
def test_an_id_token_for_another_tool_is_refused(lti):
    tamper(lti, lambda c: c.update(aud="someone-else", azp="someone-else"))
    refused_launch(lti)


@protocol_only
def test_several_audiences_need_gyrolab_as_the_authorised_party(lti):
    tamper(lti, lambda c: c.update(aud=[CLIENT_ID, "other-tool"], azp="other-tool"))
    refused_launch(lti)


@protocol_only
def test_an_unknown_deployment_is_refused(lti):
    claim = "https://purl.imsglobal.org/spec/lti/claim/deployment_id"
    tamper(lti, lambda c: c.update({claim: "deployment-of-someone-else"}))
    refused_launch(lti)


@protocol_only
def test_a_nonce_not_issued_by_this_login_is_refused(lti):
    tamper(lti, lambda c: c.update(nonce="made-up"))
    refused_launch(lti)


@protocol_only
def test_an_id_token_from_the_future_is_refused(lti):
    tamper(lti, lambda c: c.update(iat=int(time.time()) + 3600))
    refused_launch(lti)


@protocol_only
def test_an_unsigned_id_token_is_refused(lti):
    browser = lti.browser()
    page = browser.get(f"{lti.platform.url}/start?user=teacher-1&kind=deep")
    claims = jwt.decode(lti.platform.last_id_token, options={"verify_signature": False})
    unsigned = jwt.encode(claims, key=None, algorithm="none")
    posted = browser.submit_auto_form(page, {"id_token": unsigned})
    assert posted.status_code == 401 and REFUSED in posted.text


@protocol_only
def test_a_replayed_launch_is_refused(lti):
    browser = lti.browser()
    page = browser.get(f"{lti.platform.url}/start?user=teacher-1&kind=deep")
    first = browser.submit_auto_form(page)
    assert first.status_code == 200 and "Add a GyroLab activity" in first.text
    again = browser.submit_auto_form(page)  # the same id_token and state, posted once more
    assert again.status_code == 401 and REFUSED in again.text
    assert "nonce was used already" in again.text


@protocol_only
def test_a_launch_posted_from_another_browser_is_refused(lti):
    """Login CSRF: an id_token obtained in one browser, posted by another (no state cookie)."""
    attacker = lti.browser()
    page = attacker.get(f"{lti.platform.url}/start?user=teacher-1&kind=deep")
    victim = lti.browser()
    victim_page = victim.client.post(
        f"{lti.tool}/lti/launch",
        data={k: v for k, v in Browser.FIELD.findall(page.text)},
    )
    assert victim_page.status_code == 401 and "The state is not this browser" in victim_page.text
    assert "gyrolab_session" not in cookie_names(victim)


@protocol_only
def test_an_unregistered_platform_cannot_start_a_login(lti):
    page = lti.browser().get(
        f"{lti.tool}/lti/login?iss=https://evil.example&login_hint=x&target_link_uri=/"
    )
    assert page.status_code == 400 and REFUSED in page.text


@protocol_only
def test_a_launch_with_nothing_in_it_is_a_clear_page(lti):
    page = lti.browser().client.post(f"{lti.tool}/lti/launch", data={"id_token": "x" * 30_000})
    assert page.status_code == 401 and REFUSED in page.text


@protocol_only
def test_observers_are_refused_and_students_wait_for_their_teacher(lti):
    early = lti.browser().launch(lti.platform.url, user="student-1", link="link-9")
    assert early.status_code == 409 and "has not opened GyroLab in this course" in early.text
    observer = lti.browser().launch(lti.platform.url, user="observer-1", link="link-9")
    assert observer.status_code == 403 and "mentor or observer" in observer.text


@protocol_only
def test_a_student_account_launched_as_an_instructor_is_not_promoted(lti):
    with write_session() as db:
        student = make_user("li", Role.student)
        db.add(ExternalIdentity(user_id=student.id, issuer=lti.platform.url, subject="teacher-1"))
    page = lti.browser().launch(lti.platform.url, user="teacher-1", kind="deep")
    assert page.status_code == 403 and "role does not match" in page.text
    with read_session() as db:
        assert db.get(User, student.id).role == Role.student


# --- inside an LMS frame, keys, retries, registration -------------------------------------------


@protocol_only
def test_a_framed_launch_opens_gyrolab_in_a_new_window_through_a_one_time_link(lti):
    deep_link_new_assignment(lti)
    framed = lti.browser(**{"Sec-Fetch-Dest": "iframe"})
    page = framed.launch(lti.platform.url, user="teacher-1", link="link-1")
    assert page.status_code == 200 and "GyroLab opens in its own window" in page.text
    assert f"frame-ancestors {lti.platform.url}" in page.headers["content-security-policy"]
    assert "x-frame-options" not in page.headers
    assert "gyrolab_session" not in cookie_names(framed)
    link = page.text.split('href="/lti/continue/', 1)[1].split('"', 1)[0]
    window = lti.browser()
    opened = window.get(f"{lti.tool}/lti/continue/{link}")
    assert opened.status_code == 200 and "/assignments/" in str(opened.url)
    assert "gyrolab_session" in cookie_names(window)
    assert lti.browser().get(f"{lti.tool}/lti/continue/{link}").status_code == 410  # once


@protocol_only
def test_rotating_the_key_keeps_the_old_one_published_and_signs_with_the_new(lti):
    before = Browser().get(f"{lti.tool}/lti/jwks.json").json()["keys"]
    with write_session() as db:
        new = keys.rotate(db)
    after = Browser().get(f"{lti.tool}/lti/jwks.json").json()["keys"]
    assert [k["kid"] for k in after] == [new.kid, before[0]["kid"]]
    assert all("d" not in key for key in after)  # public halves only
    deep_link_new_assignment(lti)  # the platform verifies a response signed with the new key


@protocol_only
def test_a_grade_the_platform_refuses_is_kept_shown_and_retried(lti):
    deep_link_new_assignment(lti)
    teacher = lti.browser()
    dashboard = teacher.launch(lti.platform.url, user="teacher-1", link="link-1")
    learner = lti.browser()
    lab = learner.launch(lti.platform.url, user="student-2", link="link-1")
    session_id = int(urlsplit(str(lab.url)).path.rsplit("/", 1)[1])
    _record_and_submit(learner, lti.tool, session_id)
    lti.platform.fail_scores = 2
    _release(teacher, lti.tool, session_id, points="30", feedback="")
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        with read_session() as db:
            post = db.exec(select(LtiGradePost)).one()
            if post.tries:
                break
        time.sleep(0.05)
    assert post.status == "pending" and "503" in post.last_error, lti.platform.refusals
    page = without_tokens(teacher.get(str(dashboard.url)).text)
    assert "0 grades received by the learning platform, 1 waiting" in page
    assert "The last attempt failed" in page
    assert grades.send_due(post.next_try_at) == {"sent": 0, "failed": 1}  # still 503
    csrf = csrf_of(teacher, str(dashboard.url))
    sent = teacher.client.post(f"{dashboard.url}/lti/send", data={"csrf_token": csrf})
    assert "1 grades sent, 0 failed" in sent.text
    scores = arrived(lti.platform.scores, 1)
    assert scores[0]["userId"] == "student-2" and scores[0]["scoreGiven"] == 30
    wait_until_sent(1)
    with read_session() as db:
        assert db.exec(select(LtiGradePost)).one().status == "sent"


def test_the_pause_between_tries_grows_to_an_hour():
    assert [grades.pause_after(n).total_seconds() for n in (1, 2, 3, 10, 20)] == [
        30,
        60,
        120,
        3600,
        3600,
    ]


@protocol_only
def test_dynamic_registration_needs_a_live_one_time_link(lti, client):
    from app.lti.registration import new_registration_link

    assert client.get("/lti/register?token=made-up").status_code == 403
    with write_session() as db:
        token = new_registration_link(db)
    no_lms = client.get(f"/lti/register?token={token}")
    assert no_lms.status_code == 400 and "tool registration" in no_lms.text
    broken = client.get(
        f"/lti/register?token={token}&openid_configuration=http://127.0.0.1:9/nothing"
    )
    assert broken.status_code == 502  # the link survives a failed attempt
    with read_session() as db:
        assert db.exec(select(LtiPlatform)).all()[0].issuer == lti.platform.url


@protocol_only
def test_dynamic_registration_registers_the_platform_with_one_pasted_link(lti):
    from app.lti.registration import new_registration_link

    with write_session() as db:
        token = new_registration_link(db)
    configuration = f"{lti.platform.url}/.well-known/openid-configuration"
    url = f"{lti.tool}/lti/register?token={token}&openid_configuration={configuration}"
    client = lti.browser()
    refused = client.get(f"{url}&registration_token=wrong")
    assert refused.status_code == 502 and "did not complete" in refused.text
    done = client.get(f"{url}&registration_token={lti.platform.registration_token}")
    assert done.status_code == 200 and "GyroLab is registered" in done.text, done.text[-1200:]
    assert f"frame-ancestors {lti.platform.url}" in done.headers["content-security-policy"]
    sent = lti.platform.registered
    assert sent["jwks_uri"].endswith("/lti/jwks.json") and "/lti/launch" in sent["redirect_uris"][0]
    assert "contextmembership.readonly" in sent["scope"]
    with read_session() as db:
        row = db.exec(select(LtiPlatform).where(LtiPlatform.client_id == "dyn-client")).one()
        assert (row.registered_by, row.deployment_ids) == ("dynamic", "dyn-deployment")
        assert row.auth_login_url == f"{lti.platform.url}/authorize"
    again = client.get(f"{url}&registration_token={lti.platform.registration_token}")
    assert again.status_code == 403  # the link worked once


@protocol_only
def test_registering_a_platform_by_hand_checks_every_address(lti, client):
    admin = make_user("root", Role.admin)
    from tests.factories import login

    login(client, admin.username)
    bad = post_form(
        client,
        "/admin/lti/platforms",
        {**lti.platform.platform_fields(), "auth_login_url": "javascript:alert(1)"},
        page="/admin/lti",
    )
    assert bad.status_code == 400
    assert "Authentication request URL" not in bad.text or "must be a full" in bad.text
    fields = {**lti.platform.platform_fields(), "client_id": "second", "deployment_ids": "a, b"}
    saved = post_form(client, "/admin/lti/platforms", fields, page="/admin/lti")
    assert saved.status_code == 303
    page = client.get("/admin/lti").text
    assert "<code>second</code>" in page and "<code>a</code>, <code>b</code>" in page
    assert f"{lti.platform.url}" in page


def every_form_has_a_token(page: str) -> bool:
    forms = re.findall(r'<form[^>]*method="post".*?</form>', page, re.S)
    return bool(forms) and all(re.search(r'name="csrf_token" value="[^"]+"', f) for f in forms)


@protocol_only
def test_the_lms_forms_carry_their_csrf_token(lti, client):
    deep_link_new_assignment(lti)
    teacher = lti.browser()
    dashboard = teacher.launch(lti.platform.url, user="teacher-1", link="link-1")
    course = str(dashboard.url).split("/assignments/")[0]
    assert 'id="lms"' in dashboard.text and every_form_has_a_token(dashboard.text)
    assert 'id="lms"' in (page := teacher.get(course).text) and every_form_has_a_token(page)
    make_user("root", Role.admin)
    from tests.factories import login

    login(client, "root")
    assert every_form_has_a_token(client.get("/admin/lti").text)


def test_a_link_opened_from_another_lms_course_is_refused(lti):
    """Issue 31, item 3: a resource link belongs to the LMS course (context) it was placed
    in; the same link id launched from another course -- a copied course, or a forged id --
    lands in nobody's assignment but is refused with a page that says what to do."""
    deep_link_new_assignment(lti)
    link_id = next(iter(lti.platform.links))
    first = lti.browser().launch(lti.platform.url, user="teacher-1", link=link_id)
    assert first.status_code == 200 and "/assignments/" in str(first.url)  # bound to its course
    context = "https://purl.imsglobal.org/spec/lti/claim/context"
    tamper(lti, lambda c: c.update({context: {"id": "OTHER-COURSE", "title": "Other"}}))
    page = lti.browser().launch(lti.platform.url, user="teacher-1", link=link_id)
    assert page.status_code == 409, page.text[:300]
    assert "belongs to another course of your learning platform" in page.text
    page = lti.browser().launch(lti.platform.url, user="student-1", link=link_id)
    assert page.status_code == 409 and "/lab/sessions/" not in str(page.url)
    lti.platform.tamper = None
    page = lti.browser().launch(lti.platform.url, user="student-1", link=link_id)
    assert page.status_code == 200 and "/lab/sessions/" in str(page.url)  # at home: fine
