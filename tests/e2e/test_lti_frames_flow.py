"""Issue 31, item 6: GyroLab inside an LMS frame in Chromium, which blocks third-party
cookies.  The LMS's course page is on ``localhost`` and frames GyroLab on ``127.0.0.1`` --
two sites, so GyroLab's cookies in the frame are third-party.  Three browsers are played:

* the LMS offers platform storage and the browser keeps no cookie of GyroLab's inside the
  LMS at all, partitioned or not (Safari's way, and Chrome's with cookies blocked):
  the state goes through ``lti.put_data`` / ``lti.get_data``; deep linking, a student's
  launch and their return visit;
* no platform storage, third-party cookies blocked: the partitioned state cookie;
* neither: the login page offers a new window, where the launch runs first-party.
"""

from __future__ import annotations

import json

import pytest
from playwright.sync_api import expect

from tests.e2e.conftest import CHROMIUM, CHROMIUM_ARGS
from tests.lti_platform import (
    PlatformState,
    bound_socket,
    create_platform_app,
    register_with_cli,
    serving,
)

pytestmark = pytest.mark.e2e
# Chromium puts a frame of another site in a renderer process of its own (site isolation);
# on a loaded machine Playwright then lost the frame's document now and then -- the first
# framed launch showed no heading, or a later call waited for ever (about one run in two
# under a two-core load; issue 31's note).  One process for the page and its frames ends
# that; the cookie rules under test are the network service's (per top-level site), not
# the renderer's, and third_party_cookies_blocked() checks them in every test.
FRAME_ARGS = [*CHROMIUM_ARGS, "--disable-site-isolation-trials"]
LAUNCH_MS = 20_000  # a launch is several round trips, the platform's key set fetched once


@pytest.fixture
def framed_tool(live_server):
    """GyroLab served on 127.0.0.1: the run's shared installation (each test registers an
    LMS of its own: another issuer, its own courses and people, so that no test sees
    another's)."""
    return live_server


@pytest.fixture
def framed_lms(framed_tool):
    """An LMS on localhost, on a port of its own, registered with GyroLab."""
    platform_socket = bound_socket()
    platform = PlatformState(
        url=f"http://localhost:{platform_socket.getsockname()[1]}", tool_url=framed_tool.url
    )
    register_with_cli(framed_tool, platform)
    with serving(create_platform_app(platform), platform_socket):
        yield framed_tool, platform


@pytest.fixture
def chromium_profile(browser, tmp_path):
    """A Chromium profile of its own (a persistent context) with the given preferences:
    ``cookie_controls_mode`` 1 blocks third-party cookies as Chrome's setting does; a
    cookie exception with setting 2 blocks every cookie -- partitioned ones too -- of a
    site inside another (a browser that keeps no third-party cookie at all)."""
    contexts, errors = [], []

    def open_profile(preferences: dict, locale: str = "en-US"):
        folder = tmp_path / f"profile-{len(contexts)}"
        (folder / "Default").mkdir(parents=True)
        (folder / "Default" / "Preferences").write_text(json.dumps(preferences))
        context = browser.browser_type.launch_persistent_context(
            str(folder),
            executable_path=str(CHROMIUM),
            headless=True,
            args=FRAME_ARGS,
            locale=locale,
            viewport={"width": 1280, "height": 860},
        )
        context.set_default_timeout(10_000)
        context.on("page", lambda page: watch(page, errors))
        contexts.append(context)
        return context

    yield open_profile
    for context in contexts:
        context.close()
    assert not errors, errors


def watch(page, errors: list[str]) -> None:
    """Script errors and anything the CSP blocked, on every page and frame."""
    page.on("pageerror", lambda error: errors.append(f"page error: {error}"))
    page.on(
        "console",
        lambda message: (
            errors.append(message.text) if "Content Security Policy" in message.text else None
        ),
    )


def blocking_third_party(_server, _platform) -> dict:
    return {"profile": {"cookie_controls_mode": 1, "block_third_party_cookies": True}}


def blocking_every_framed_cookie(server, platform) -> dict:
    pair = f"{server.url},{platform.url}"  # GyroLab's cookies inside the LMS's pages
    return {"profile": {"content_settings": {"exceptions": {"cookies": {pair: {"setting": 2}}}}}}


def third_party_cookies_blocked(frame) -> bool:
    """Whether this Chromium refuses GyroLab an ordinary cookie inside the LMS's frame
    (``frame``: its FrameLocator; a locator's evaluate has a timeout, a frame's has none)."""
    return not frame.locator(":root").evaluate(
        "() => { document.cookie = 'probe=1; SameSite=None; Secure; path=/';"
        " return document.cookie.includes('probe=1'); }",
        timeout=LAUNCH_MS,
    )


def storage_calls(page) -> list[str]:
    """The platform storage messages the LMS's page answered."""
    return page.locator(":root").evaluate("() => window.platformStorageCalls", timeout=LAUNCH_MS)


def opened_in_frame(page, url: str, heading: str):
    """The LMS's course page at ``url``, GyroLab's frame showing ``heading``."""
    page.goto(url)
    frame = page.frame_locator("#tool")
    expect(frame.locator("h1")).to_have_text(heading, timeout=LAUNCH_MS)
    return frame


def open_in_new_window(page, frame):
    with page.expect_popup() as popup:
        frame.get_by_role("link", name="Open GyroLab").click()
    window = popup.value
    window.wait_for_load_state()
    return window


def test_platform_storage_carries_deep_linking_a_launch_and_a_return_visit(
    framed_lms, chromium_profile
):
    server, platform = framed_lms
    platform.storage_target = "_parent"
    no_cookies = blocking_every_framed_cookie(server, platform)

    teacher = chromium_profile(no_cookies).new_page()
    course = f"{platform.url}/course?user=teacher-1&kind=deep"
    frame = opened_in_frame(teacher, course, "Add a GyroLab activity")
    assert third_party_cookies_blocked(frame)
    frame.locator("input[name=title]").fill("North in a frame 框内寻北")
    frame.get_by_role("button", name="Create and add").click()
    expect(frame.locator("body")).to_contain_text("added 1")
    calls = storage_calls(teacher)
    assert calls.count("lti.put_data") == 2 and calls.count("lti.get_data") == 2
    assert platform.links["link-1"]["title"] == "North in a frame 框内寻北"

    student = chromium_profile(no_cookies, locale="zh-CN").new_page()
    student.goto(f"{platform.url}/course?user=student-1&link=link-1")
    frame = student.frame_locator("#tool")
    expect(frame.locator("h1")).to_have_text("GyroLab 在新窗口中打开", timeout=LAUNCH_MS)
    assert storage_calls(student).count("lti.get_data") == 2
    with student.expect_popup() as popup:
        frame.get_by_role("link", name="打开 GyroLab").click()
    lab = popup.value
    lab.wait_for_url(f"{server.url}/lab/sessions/*")
    expect(lab.locator("h1")).to_contain_text("框内寻北")
    first_visit = lab.url
    lab.close()

    # the return visit: a new launch from the course page, the same session
    student.goto(f"{platform.url}/course?user=student-1&link=link-1")
    expect(frame.locator("h1")).to_have_text("GyroLab 在新窗口中打开", timeout=LAUNCH_MS)
    with student.expect_popup() as popup:
        frame.get_by_role("link", name="打开 GyroLab").click()
    popup.value.wait_for_url(first_visit)


def test_without_platform_storage_the_partitioned_state_cookie_carries_the_launch(
    framed_lms, chromium_profile
):
    server, platform = framed_lms
    teacher = chromium_profile(blocking_third_party(server, platform)).new_page()
    teacher.goto(f"{platform.url}/course?user=teacher-1&kind=deep")
    frame = teacher.frame_locator("#tool")
    expect(frame.locator("h1")).to_have_text("Add a GyroLab activity", timeout=LAUNCH_MS)
    assert third_party_cookies_blocked(frame)
    frame.locator("input[name=title]").fill("Partitioned")
    frame.get_by_role("button", name="Create and add").click()
    expect(frame.locator("body")).to_contain_text("added 1")
    partitioned = [c for c in teacher.context.cookies() if c["name"].startswith("lti1p3-state")]
    assert partitioned and all(c.get("partitionKey") for c in partitioned)

    student = chromium_profile(blocking_third_party(server, platform)).new_page()
    student.goto(f"{platform.url}/course?user=student-1&link=link-1")
    frame = student.frame_locator("#tool")
    lab = open_in_new_window(student, frame)
    lab.wait_for_url(f"{server.url}/lab/sessions/*")
    expect(lab.locator("h1")).to_contain_text("Partitioned")


def test_with_neither_the_login_page_opens_the_launch_in_a_new_window(framed_lms, chromium_profile):
    server, platform = framed_lms
    teacher = chromium_profile(blocking_every_framed_cookie(server, platform)).new_page()
    teacher.goto(f"{platform.url}/course?user=teacher-1&kind=deep")
    frame = teacher.frame_locator("#tool")
    expect(frame.locator("#lti-new-window")).to_be_visible(timeout=LAUNCH_MS)
    expect(frame.locator("#lti-new-window")).to_contain_text("window of its own")
    picker = open_in_new_window(teacher, frame)
    expect(picker.locator("h1")).to_have_text("Add a GyroLab activity")  # first-party now
    picker.locator("input[name=title]").fill("New window")
    with picker.expect_navigation(url=f"{platform.url}/deep-link-return"):
        picker.get_by_role("button", name="Create and add").click()
    expect(picker.locator("body")).to_contain_text("added 1")
