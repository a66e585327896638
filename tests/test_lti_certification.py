"""Issue 31, item 7 (the known-bad payloads): the checks 1EdTech's LTI 1.3 certification
runs against a tool's launch endpoint, each refused with a clear page and no account.
(The valid-launch variants of the certification -- unknown or no role, no context, no
personal data -- are not yet here.)"""

from __future__ import annotations

import time

import jwt
import pytest
from sqlmodel import select

from app.db import read_session
from app.models import ExternalIdentity
from tests.test_lti import REFUSED, cookie_names, lti  # noqa: F401 (the fixture)

pytestmark = pytest.mark.one_backend

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
