"""Issue 31, item 6 (the protocol): a launch inside an LMS frame where the browser keeps
no third-party cookies -- the login page that stores the state in the LMS's platform
storage, the launch confirmed from it, and what is refused.  The same flows in Chromium
with third-party cookies blocked are in tests/e2e/test_lti_frames_flow.py."""

from __future__ import annotations

import re
from urllib.parse import parse_qs, urlsplit

import pytest

from tests.lti_platform import Browser
from tests.test_lti import REFUSED, deep_link_new_assignment, lti  # noqa: F401 (the fixture)

# slow: a real LMS and GyroLab served on loopback
pytestmark = [pytest.mark.one_backend, pytest.mark.slow]
FRAME = {"Sec-Fetch-Dest": "iframe"}


def login_in_frame(lti, user="student-1"):  # noqa: F811
    """The LMS's frame opens GyroLab's login: the page, and the browser that got it."""
    lti.platform.storage_target = "_parent"
    browser = lti.browser(**FRAME)
    page = browser.get(f"{lti.platform.url}/start?user={user}&link=link-1")
    return page, browser


def cookieless_launch(lti, page, browser):  # noqa: F811
    """The platform's form post reaching GyroLab with no cookie (a blocked third party)."""
    auto_post = browser.get(browser.data(page, "auth-url"))
    return Browser(headers={"Accept-Language": "en", **FRAME}).submit_auto_form(auto_post)


def hidden(page, name: str) -> str:
    return re.search(rf'name="{name}" value="([^"]*)"', page.text).group(1)


def test_a_framed_login_offered_storage_gives_a_page_that_stores_the_state(lti):  # noqa: F811
    page, _browser = login_in_frame(lti)
    assert page.status_code == 200 and 'data-mode="login"' in page.text
    auth = Browser.data(page, "auth-url")
    query = parse_qs(urlsplit(auth).query)
    assert auth.startswith(f"{lti.platform.url}/authorize?")
    assert Browser.data(page, "state") == query["state"][0]
    assert Browser.data(page, "nonce") == query["nonce"][0]
    assert Browser.data(page, "target") == "_parent"
    assert Browser.data(page, "platform-origin") == lti.platform.url
    assert f"frame-ancestors {lti.platform.url}" in page.headers["content-security-policy"]
    # the state cookie too, partitioned: browsers with CHIPS keep it for this LMS alone
    cookie = page.headers["set-cookie"]
    assert "Partitioned" in cookie and "SameSite=none" in cookie and "Secure" in cookie
    # the new-window fallback starts the same login without the storage target
    fallback = re.search(r'href="(/lti/login\?[^"]+)"', page.text).group(1)
    assert "lti_storage_target" not in fallback and "login_hint=student-1" in fallback


def test_a_launch_with_no_cookie_is_confirmed_from_platform_storage(lti):  # noqa: F811
    deep_link_new_assignment(lti)
    page, browser = login_in_frame(lti)
    check = cookieless_launch(lti, page, browser)
    assert check.status_code == 200 and 'data-mode="check"' in check.text, check.text[:300]
    state = Browser.data(check, "state")
    assert state == Browser.data(page, "state")
    assert Browser.data(check, "nonce") == Browser.data(page, "nonce")
    assert "frame-ancestors" in check.headers["content-security-policy"]
    # the page's script read state_<state> back from the LMS and posts the launch again
    fields = {n: hidden(check, n) for n in ("id_token", "state", "lti_storage_target")}
    confirmed = Browser(headers=FRAME).client.post(
        f"{lti.tool}/lti/launch", data={**fields, "lti_platform_state": state}
    )
    assert confirmed.status_code == 200 and "/lti/continue/" in confirmed.text, confirmed.text
    # ... once: the nonce is spent
    again = Browser(headers=FRAME).client.post(
        f"{lti.tool}/lti/launch", data={**fields, "lti_platform_state": state}
    )
    assert again.status_code == 401 and REFUSED in again.text


@pytest.mark.parametrize("told", ["another", "made-up"])
def test_a_state_the_storage_does_not_confirm_is_refused(lti, told):  # noqa: F811
    deep_link_new_assignment(lti)
    page, browser = login_in_frame(lti)
    check = cookieless_launch(lti, page, browser)
    fields = {n: hidden(check, n) for n in ("id_token", "state", "lti_storage_target")}
    if told == "another":  # the storage answered with a state of another login
        fields["lti_platform_state"] = "state-of-another-login"
    else:  # a state GyroLab never issued, "confirmed" by a forged post
        fields["state"] = fields["lti_platform_state"] = "state-never-issued"
    refused = Browser(headers=FRAME).client.post(f"{lti.tool}/lti/launch", data=fields)
    assert refused.status_code == 401 and REFUSED in refused.text
    assert "gyrolab_session" not in refused.headers.get("set-cookie", "")


def test_without_storage_or_cookie_the_login_page_offers_a_new_window(lti):  # noqa: F811
    page, browser = login_in_frame(lti)
    state = Browser.data(page, "state")
    # the state-check answers for this browser's cookie only
    assert browser.get(f"{lti.tool}/lti/state-check?state={state}").json() == {"cookie": True}
    stranger = Browser()
    assert stranger.get(f"{lti.tool}/lti/state-check?state={state}").json() == {"cookie": False}
    assert 'id="lti-new-window" hidden' in page.text  # shown by the script when both fail
