"""Issue 35 item 2 in a real browser: the class board on a 1920 × 1080 projector in both
languages -- the pooled numbers large enough for the back of the room, every chart drawn,
nothing off screen, a snapshot kept."""

from __future__ import annotations

import pytest
from playwright.sync_api import expect

from tests.e2e.conftest import expect_chart_drawn, log_in

pytestmark = pytest.mark.e2e

WORDS = {
    "en": ("The class measures the Earth", "Earth rate"),
    "zh-CN": ("全班共同测量地球", "地球自转角速度"),
}


@pytest.mark.parametrize("language", ["en", "zh-CN"])
def test_the_class_board_on_a_projector(demo_server, new_page, language):
    server, credentials = demo_server
    page = new_page()
    page.set_viewport_size({"width": 1920, "height": 1080})
    page.context.add_cookies([{"name": "gyrolab_lang", "value": language, "url": server.url}])
    log_in(page, server.url, "teacher", credentials["teacher"])
    page.goto(f"{server.url}/courses/1/assignments/1")
    with page.expect_navigation():
        page.locator("#board-link").click()
    title, rate = WORDS[language]
    expect(page.locator("h1")).to_contain_text(title)
    number = page.locator("#board-rate .big")
    expect(number).to_contain_text(rate)
    size = number.evaluate("el => parseFloat(getComputedStyle(el).fontSize)")
    assert size >= 40, f"{size}px: too small for the back of a room"
    charts = page.locator(".chart[data-figure]")
    assert charts.count() >= 3
    for index in range(charts.count()):
        expect_chart_drawn(charts.nth(index))
    # the charts sit side by side on a projector, all in the first screen's width
    boxes = [charts.nth(i).bounding_box() for i in range(3)]
    assert len({round(b["y"]) for b in boxes}) == 1 and all(
        b["x"] + b["width"] <= 1920 for b in boxes
    )
    assert not page.evaluate("() => document.documentElement.scrollWidth > window.innerWidth + 1")
    assert "student1" not in page.locator("#class-board").inner_text()  # no names unless asked

    if language == "en":
        with page.expect_navigation():
            page.get_by_role("button", name="Keep a snapshot").click()
        expect(page.locator("h1")).to_contain_text("Snapshot of")
        expect(page.locator("#board-rate .big")).to_contain_text("Earth rate")
