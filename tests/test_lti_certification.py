"""Issue 31, item 7: the checks 1EdTech's LTI 1.3 certification runs against a tool's
launch endpoint -- the known-bad payloads, each refused with a clear page and no account,
and the valid variants (several roles, short role names, an unknown role, no role, e-mail
only, names only, no personal data, no context), each accepted with a sensible account."""

from __future__ import annotations

import time

import jwt
import pytest
from sqlmodel import select

from app.db import read_session
from app.models import Course, ExternalIdentity, Role, User
from tests.test_lti import (  # noqa: F401 (the fixture)
    REFUSED,
    _launch_id,
    cookie_names,
    deep_link_new_assignment,
    lti,
)

# slow: a real LMS and GyroLab served on loopback
pytestmark = [pytest.mark.one_backend, pytest.mark.slow]

LTI = "https://purl.imsglobal.org/spec/lti/claim/"


def post_token(lti, edit=None, headers=None, kind="deep"):  # noqa: F811
    """A launch whose ID token is the platform's own, edited and re-signed with the
    platform's key (or with ``headers`` of the test's choosing)."""
    browser = lti.browser()
    page = browser.get(f"{lti.platform.url}/start?user=teacher-1&kind={kind}")
    claims = jwt.decode(lti.platform.last_id_token, options={"verify_signature": False})
    kid = jwt.get_unverified_header(lti.platform.last_id_token)["kid"]
    if edit is not None:
        claims = edit(claims) or claims
    token = jwt.encode(claims, lti.platform.private_key, algorithm="RS256",
                       headers={"kid": kid} if headers is None else headers)  # fmt: skip
    posted = browser.submit_auto_form(page, {"id_token": token})
    return posted, browser


def assert_refused(posted, browser) -> None:
    assert 400 <= posted.status_code < 500, posted.text[:300]
    assert REFUSED in posted.text and "Traceback" not in posted.text
    assert "gyrolab_session" not in cookie_names(browser)
    with read_session() as db:
        assert db.exec(select(ExternalIdentity)).first() is None


def without(name):
    def edit(claims):
        claims.pop(name, None)
        return claims

    return edit


def test_a_token_without_a_key_id_is_refused(lti):  # noqa: F811
    assert_refused(*post_token(lti, headers={}))


def test_a_token_with_an_unknown_key_id_is_refused(lti):  # noqa: F811
    assert_refused(*post_token(lti, headers={"kid": "no-such-key"}))


@pytest.mark.parametrize("version", ["1.2.0", "1.1", None])
def test_a_wrong_or_missing_lti_version_is_refused(lti, version):  # noqa: F811
    def edit(claims):
        if version is None:
            claims.pop(LTI + "version", None)
        else:
            claims[LTI + "version"] = version
        return claims

    assert_refused(*post_token(lti, edit))


def test_a_jwt_that_is_not_an_lti_launch_is_refused(lti):  # noqa: F811
    def edit(claims):
        return {k: v for k, v in claims.items() if not k.startswith("https://purl.imsglobal")}

    assert_refused(*post_token(lti, edit))


@pytest.mark.parametrize(
    ("claim", "kind"),
    [
        (LTI + "message_type", "deep"),
        (LTI + "roles", "deep"),
        (LTI + "deployment_id", "deep"),
        (LTI + "resource_link", "link"),
        ("sub", "deep"),
    ],
)
def test_a_launch_missing_a_required_claim_is_refused(lti, claim, kind):  # noqa: F811
    assert_refused(*post_token(lti, without(claim), kind=kind))


@pytest.mark.parametrize("field", ["iat", "exp"])
def test_bad_times_are_refused(lti, field):  # noqa: F811
    def edit(claims):
        claims[field] = int(time.time()) + 7200 if field == "iat" else int(time.time()) - 7200
        return claims

    assert_refused(*post_token(lti, edit))


# --- the valid launches -------------------------------------------------------------------------

LIS = "http://purl.imsglobal.org/vocab/lis/v2/membership#"
PERSONAL = ("name", "given_name", "family_name", "middle_name", "email", "picture")


def account_of(subject: str) -> User:
    with read_session() as db:
        return db.exec(
            select(User)
            .join(ExternalIdentity, ExternalIdentity.user_id == User.id)
            .where(ExternalIdentity.subject == subject)
        ).one()


def launched(lti, user: str, edit, **params):  # noqa: F811
    """A launch of ``user`` whose claims the platform edits before signing."""
    lti.platform.tamper = edit
    try:
        return lti.browser().launch(lti.platform.url, user=user, **params)
    finally:
        lti.platform.tamper = None


def with_roles(*roles):
    def edit(claims):
        claims[LTI + "roles"] = list(roles)
        return claims

    return edit


@pytest.mark.parametrize(
    "roles",
    [
        [
            LIS + "Learner",
            LIS + "Mentor",
            "http://purl.imsglobal.org/vocab/lis/v2/institution/person#Student",
        ],
        ["Learner"],
        ["http://purl.imsglobal.org/vocab/lis/v2/membership#Unknown"],
        ["urn:example:role:lab-visitor"],
        [],
    ],
    ids=["several", "short-name", "unknown-lis", "unknown-urn", "none"],
)
def test_a_learner_launch_with_any_role_but_a_teachers_lands_in_the_lab(lti, roles):  # noqa: F811
    deep_link_new_assignment(lti)
    page = launched(lti, "student-1", with_roles(*roles), link="link-1")
    assert page.status_code == 200 and "/lab/sessions/" in str(page.url), page.text[:300]
    student = account_of("student-1")
    assert student.role == Role.student and student.display_name == "Li Wei 李伟"


def test_a_teacher_with_short_role_names_and_several_roles_is_a_teacher(lti):  # noqa: F811
    deep_link_new_assignment(lti)
    page = launched(lti, "teacher-1", with_roles("Instructor", "Learner"), link="link-1")
    assert page.status_code == 200 and "/assignments/" in str(page.url), page.text[:300]
    assert account_of("teacher-1").role == Role.teacher


def personal(keep: tuple[str, ...]):
    def edit(claims):
        for name in PERSONAL:
            if name not in keep:
                claims.pop(name, None)
        return claims

    return edit


@pytest.mark.parametrize(
    ("keep", "name", "email"),
    [
        (("email",), "liwei", "liwei@uni.example"),
        (("name",), "Li Wei 李伟", None),
        (("given_name", "family_name"), "Li Wei", None),
        ((), "Test LMS · ", None),
    ],
    ids=["email-only", "name-only", "given-and-family", "no-personal-data"],
)
def test_a_launch_with_little_personal_data_makes_a_named_account(lti, keep, name, email):  # noqa: F811
    deep_link_new_assignment(lti)

    def edit(claims):  # a newcomer the LMS's roster has not listed
        claims = personal(keep)(claims)
        claims["sub"] = "newcomer-1"
        if keep == ("given_name", "family_name"):
            claims["given_name"], claims["family_name"] = "Li", "Wei"
        return claims

    page = launched(lti, "student-1", edit, link="link-1")
    assert page.status_code == 200 and "/lab/sessions/" in str(page.url), page.text[:300]
    student = account_of("newcomer-1")
    assert student.display_name.startswith(name) and student.email == email
    assert student.display_name != "newcomer-1"  # never the platform's opaque id
    assert student.username and student.role == Role.student
    # the name shows in the page's header, so the student knows whose session it is
    assert student.display_name in page.text


def test_a_launch_with_no_context_gets_the_deployments_course(lti):  # noqa: F811
    def no_context(claims):
        claims.pop(LTI + "context", None)
        return claims

    teacher = lti.browser()
    lti.platform.tamper = no_context
    picker = teacher.launch(lti.platform.url, user="teacher-1", kind="deep")
    assert picker.status_code == 200 and "Add a GyroLab activity" in picker.text, picker.text[:300]
    back = teacher.client.post(
        f"{lti.tool}/lti/deep-link",
        data={"launch_id": _launch_id(picker.text), "new": "1", "title": "Outside 课外"},
    )
    assert back.status_code == 200 and 'name="JWT"' in back.text, back.text[-800:]
    assert "added 1" in teacher.submit_auto_form(back).text
    page = lti.browser().launch(lti.platform.url, user="student-1", link="link-1")
    lti.platform.tamper = None
    assert page.status_code == 200 and "/lab/sessions/" in str(page.url), page.text[:300]
    assert "Outside 课外" in page.text
    with read_session() as db:
        (course,) = db.exec(select(Course)).all()
        assert course.name == "Test LMS · GyroLab"
