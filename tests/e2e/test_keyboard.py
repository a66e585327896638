"""The whole lab without a mouse: a student logs in, records part B by typing into the
readings grid, turns the virtual table and starts and stops the simulated gyro, writes a
discussion and submits; the teacher reviews and releases the grade -- every step by the
keyboard (Tab, Enter, typing), checked by axe on the way."""

from __future__ import annotations

import pytest

from app.cli.demo import DEMO_ASSIGNMENT
from tests.e2e.conftest import axe_problems
from tests.factories import VERTICAL

pytestmark = pytest.mark.e2e


def tab_to(page, selector: str, limit: int = 250) -> None:
    """Press Tab until the focused element matches ``selector`` (as a keyboard user does)."""
    for _ in range(limit):
        if page.evaluate("s => !!document.activeElement?.matches(s)", selector):
            return
        page.keyboard.press("Tab")
    raise AssertionError(f"Tab never reached {selector}")


def focused(page, selector: str) -> bool:
    return page.evaluate("s => !!document.activeElement?.matches(s)", selector)


def log_in_by_keys(page, url: str, username: str, password: str) -> None:
    page.goto(f"{url}/login")
    tab_to(page, "input[name=username]")
    page.keyboard.type(username)
    page.keyboard.press("Tab")
    page.keyboard.type(password)
    with page.expect_navigation():
        page.keyboard.press("Enter")
    assert "/login" not in page.url


def test_the_whole_lab_and_its_review_by_keyboard_only(demo_server, browser):
    server, credentials = demo_server
    context = browser.new_context(locale="en-US", viewport={"width": 1366, "height": 900})
    page = context.new_page()
    page.on("dialog", lambda dialog: dialog.accept())  # Enter on the browser's own dialog
    log_in_by_keys(page, server.url, "student3", credentials["student3"])  # part A done
    page.goto(f"{server.url}/lab")
    # the demo assignment's session (another test on this server may have given student3
    # a newer one, listed first: the partners' flow)
    demo_session = page.locator("main a[href^='/lab/sessions/']", has_text=DEMO_ASSIGNMENT)
    tab_to(page, f"main a[href='{demo_session.first.get_attribute('href')}']")
    with page.expect_navigation():
        page.keyboard.press("Enter")
    session_url = page.url
    assert axe_problems(page) == []

    # part A: re-record position 1 with the simulated gyro -- choose the method and the
    # position, turn the table, start, stop, start again and keep the whole recording
    heading = "#part-heading"
    tab_to(page, f"{heading} .method-tab[data-method=simulator]")
    page.keyboard.press("Enter")
    assert page.get_attribute(f"{heading} .method-tab[data-method=simulator]", "aria-pressed")
    tab_to(page, f"{heading} .step[data-position='1']")
    page.keyboard.press("Enter")
    tab_to(page, f"{heading} .turn")
    page.keyboard.press("Enter")
    page.wait_for_function("() => document.activeElement?.classList.contains('start-sim')")
    assert "1" in page.inner_text(f"{heading} .table-position")
    assert axe_problems(page) == []
    page.keyboard.press("Enter")  # start …
    page.wait_for_function("() => document.activeElement?.classList.contains('stop-sim')")
    page.keyboard.press("Enter")  # … and stop at once
    page.wait_for_function(
        "() => !document.querySelector('#part-heading .start-sim').disabled", timeout=15_000
    )
    tab_to(page, f"{heading} .speed")
    page.keyboard.press("End")  # the fastest replay
    tab_to(page, f"{heading} .start-sim")
    page.keyboard.press("Enter")
    page.wait_for_function(
        "() => document.activeElement?.classList.contains('trim-range')", timeout=30_000
    )
    assert page.is_visible(f"{heading} .trim-box")  # the whole run, to trim or keep
    tab_to(page, f"{heading} .keep-all")
    with page.expect_navigation():
        page.keyboard.press("Enter")
    page.wait_for_function("() => document.getElementById('lab-announcer').textContent !== ''")
    assert "Saved" in page.inner_text("#lab-announcer")

    # part B: type the handout's vertical readings into the grid, row by row
    latitude = "#part-latitude"
    tab_to(page, f"{latitude} .method-tab[data-method=manual]")
    page.keyboard.press("Enter")
    tab_to(page, f"{latitude} .readings-grid tbody input")
    for row in range(10):
        for position in range(1, 5):
            page.keyboard.type(f"{VERTICAL[position][row]}")
            page.keyboard.press("Tab")
    assert "40 readings" in page.inner_text(f"{latitude} .grid-status")
    tab_to(page, f"{latitude} .save-manual")
    with page.expect_navigation():
        page.keyboard.press("Enter")
    page.wait_for_function("() => document.getElementById('lab-announcer').textContent !== ''")
    announced = page.inner_text("#lab-announcer")
    assert "Saved" in announced and "40.73°" in announced  # the new result, read out
    assert focused(page, f"{latitude} .save-manual")  # the keyboard is where it was
    assert axe_problems(page) == []

    # the discussion, then submit (the confirmation is the browser's dialog: Enter)
    tab_to(page, "#discussion-text")
    page.keyboard.type("Typed without a mouse.")
    tab_to(page, "#save-discussion")
    with page.expect_navigation():
        page.keyboard.press("Enter")
    tab_to(page, "#submit-session")
    with page.expect_navigation():
        page.keyboard.press("Enter")
    assert "submitted" in page.inner_text("#session-status").lower()
    session_id = session_url.rstrip("/").rsplit("/", 1)[1]
    context.close()

    # the teacher reviews and releases, by keyboard too
    context = browser.new_context(locale="en-US", viewport={"width": 1366, "height": 900})
    page = context.new_page()
    page.on("dialog", lambda dialog: dialog.accept())
    log_in_by_keys(page, server.url, "teacher", credentials["teacher"])
    page.goto(f"{server.url}/review/sessions/{session_id}")
    assert "Typed without a mouse." in page.inner_text("#student-discussion")
    tab_to(page, "textarea[name=feedback]")
    page.keyboard.type("Clean data; well reasoned.")
    tab_to(page, "#points")
    page.keyboard.type("92")
    tab_to(page, "#release-button")
    with page.expect_navigation():
        page.keyboard.press("Enter")
    assert "graded" in page.inner_text("#session-status").lower()
    assert axe_problems(page) == []
    context.close()
