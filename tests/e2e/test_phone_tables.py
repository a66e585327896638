"""Issue 34 item 6: the student's list tables work on a phone.  At 390 px each row is a
card (every value under its column's name, the row's action a full-width button), nothing
sits off screen and no word is cut; at 1366 px they are ordinary tables.  Both languages."""

from __future__ import annotations

import pytest

from tests.e2e.conftest import log_in

pytestmark = pytest.mark.e2e

LABELS = {"en": ("Due", "Status", "Teacher's feedback"), "zh-CN": ("截止", "状态", "老师的反馈")}

OFF_SCREEN = """selector => [...document.querySelectorAll(selector)]
    .filter(el => { const r = el.getBoundingClientRect();
                    return r.width === 0 || r.left < -0.5 || r.right > window.innerWidth + 0.5; })
    .map(el => el.textContent.trim().slice(0, 40))"""

LABEL_OF = """el => getComputedStyle(el, '::before').content.replace(/^"|"$/g, '')"""

LINES = """el => el.getClientRects().length"""


def test_list_tables_are_cards_on_a_phone_and_tables_on_a_laptop(demo_server, new_page):
    server, credentials = demo_server
    page = new_page()
    log_in(page, server.url, "student1", credentials["student1"])
    for language, (due, status, feedback) in LABELS.items():
        page.context.add_cookies([{"name": "gyrolab_lang", "value": language, "url": server.url}])
        for width in (390, 1366):
            page.set_viewport_size({"width": width, "height": 844})
            page.goto(f"{server.url}/lab")
            where = f"{language} at {width} px"
            for table in ("#assignment-list", "#sessions"):
                cells = f"{table} td, {table} td .button, {table} td button"
                assert page.evaluate(OFF_SCREEN, cells) == [], f"{table} off screen, {where}"
            action = page.locator("#assignment-list td.card-action :is(a, button)").first
            box = action.bounding_box()
            assert box["height"] >= 24 and box["width"] >= 24
            badge = page.locator("#sessions .badge").last
            assert badge.evaluate(LINES) == 1, f"the status is broken across lines, {where}"
            page.goto(f"{server.url}/")
            assert page.evaluate(OFF_SCREEN, "#work-list td") == [], where
            head = page.locator("#work-list thead")
            header = head.locator("th").first
            if width == 390:
                assert head.bounding_box()["width"] <= 1  # read by screen readers only
                assert box["width"] >= width * 0.6  # the row's action spans its card
                due_cell = page.locator("#assignment-list td[data-label]").nth(1)
                work = page.locator("#work-list td[data-label]")
                shown = [work.nth(i).evaluate(LABEL_OF) for i in range(work.count())]
                assert status in shown and feedback in shown, shown
                page.goto(f"{server.url}/lab")
                assert due_cell.evaluate(LABEL_OF) == due
            else:
                assert header.is_visible() and header.bounding_box()["width"] > 40
