"""Lab partners at one bench, in two browsers: one records, the other's page follows."""

from __future__ import annotations

import re

import pytest
from playwright.sync_api import expect

from tests.e2e.conftest import log_in

pytestmark = pytest.mark.e2e
TITLE = "Partners bench 小组实验"


def test_partners_share_one_session_live(demo_server, new_page):
    server, credentials = demo_server
    teacher = new_page()
    log_in(teacher, server.url, "teacher", credentials["teacher"])
    teacher.goto(f"{server.url}/courses")
    teacher.locator("main a[href^='/courses/']").first.click()
    form = teacher.locator("form[action$='/assignments']")
    form.locator("input[name=title]").fill(TITLE)
    form.locator("details.grading-fields summary").click()
    form.locator("select[name=group_size]").select_option("2")
    with teacher.expect_navigation():
        form.locator("button[type=submit]").click()
    expect(teacher.locator("h1")).to_contain_text(TITLE)

    starter = new_page()
    log_in(starter, server.url, "student3", credentials["student3"])
    starter.goto(f"{server.url}/lab")
    starter.locator("#assignments tr", has_text=TITLE).locator("button").click()
    starter.wait_for_url(re.compile(r".*/lab/sessions/\d+$"))
    code = starter.locator("#partner-code").inner_text()
    assert re.fullmatch(r"[A-Z2-9]{6}", code)

    partner = new_page(locale="zh-CN")
    log_in(partner, server.url, "student1", credentials["student1"])
    partner.goto(f"{server.url}/lab")
    partner.locator("#join-group input[name=code]").fill(code.lower())  # typed in any case
    with partner.expect_navigation():
        partner.locator("#join-group button").click()
    assert partner.url == starter.url
    expect(partner.locator("#partners")).to_contain_text("Zhang San")
    expect(partner.locator("#leave-group")).to_be_visible()  # nothing recorded yet

    # the starter types part A; the partner's open page follows without a reload by hand
    starter.reload()
    grid = starter.locator("#part-heading .readings-grid tbody tr")
    for row in range(10):
        for column in range(4):
            value = 10 - 10 * (column % 2) + row / 100
            grid.nth(row).locator("input").nth(column).fill(f"{value:.2f}")
    with starter.expect_navigation():
        starter.locator("#part-heading .save-manual").click()
    expect(partner.locator("#part-heading .step[data-position='4']")).to_contain_text(
        "n = 10", timeout=15_000
    )
    expect(partner.locator("#leave-group")).to_have_count(0)  # recording started: stays
