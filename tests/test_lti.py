"""GyroLab as an LTI 1.3 tool against a real platform on loopback (tests/lti_platform.py,
built on lti1p3platform): deep linking, launches, roster sync, grade passback with
retries, dynamic registration, key rotation -- and the launch's security checks, each
refused with a clear page and nobody logged in."""

from __future__ import annotations

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
    LabSession,
    LtiGradePost,
    LtiKey,
    LtiPlatform,
    Role,
    User,
)
from tests.e2e.conftest import free_port
from tests.factories import CSRF_RE, HEADING, VERTICAL, make_user, post_form, without_tokens
from tests.lti_platform import (
    CLIENT_ID,
    DEPLOYMENT_ID,
    Browser,
    PlatformState,
    create_platform_app,
    serving,
)

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
    tool_port, platform_port = free_port(), free_port()
    tool = f"http://127.0.0.1:{tool_port}"
    state = PlatformState(url=f"http://127.0.0.1:{platform_port}", tool_url=tool)
    fields = state.platform_fields()
    with write_session() as db:
        add_platform(
            db,
            PlatformFields(
                **{k: v for k, v in fields.items() if k != "deployment_ids"},
                deployment_ids=[fields["deployment_ids"]],
            ),
        )
    with serving(app, tool_port), serving(create_platform_app(state), platform_port):
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
    assert "1 grades received by the learning platform, 0 waiting" in without_tokens(
        teacher.get(str(dashboard.url)).text
    )


def arrived(scores: list, count: int, seconds: float = 10) -> list:
    """The platform's scores once ``count`` have come (the sender works after the release)."""
    deadline = time.monotonic() + seconds
    while len(scores) < count and time.monotonic() < deadline:
        time.sleep(0.05)
    return scores


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
