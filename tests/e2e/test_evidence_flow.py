"""Issue 35 item 1 in a real browser: a student types the handout's table into an
assignment; the teacher's class table shows the evidence badges and the grading desk the
sentences with their numbers, at 390 and 1366 px, in English and Chinese."""

from __future__ import annotations

import re

import pytest
from playwright.sync_api import expect

from tests.e2e.conftest import expect_chart_drawn, log_in
from tests.e2e.test_forms_flow import in_each_language_and_width
from tests.e2e.test_lab_flow import paste, table

pytestmark = pytest.mark.e2e
TITLE = "Evidence bench 证据"
WORDS = {
    "en": ("Data evidence", "readings match the handout's example table"),
    "zh-CN": ("数据证据", "与讲义示例表"),
}


def test_the_desk_shows_the_evidence_of_typed_readings(demo_server, new_page):
    server, credentials = demo_server
    teacher = new_page()
    log_in(teacher, server.url, "teacher", credentials["teacher"])
    teacher.goto(f"{server.url}/courses/1")
    form = teacher.locator("form[action$='/assignments']")
    form.locator("input[name=title]").fill(TITLE)
    with teacher.expect_navigation():
        form.locator("button[type=submit]").click()
    assignment_url = teacher.url

    student = new_page()
    log_in(student, server.url, "student2", credentials["student2"])
    student.goto(f"{server.url}/lab")
    student.locator("#assignment-list tr", has_text=TITLE).locator(
        ".card-action :is(a, button)"
    ).click()
    student.wait_for_url(re.compile(r".*/lab/sessions/\d+$"))
    rows = table("handout_horizontal.csv")
    paste(
        student, "#part-heading .readings-grid tbody input", "\n".join("\t".join(r) for r in rows)
    )
    with student.expect_navigation():
        student.locator("#part-heading .save-manual").click()
    expect(student.locator("#data-evidence")).to_have_count(0)  # never on the student's page

    teacher.goto(assignment_url)
    badge = teacher.locator("#class-table .badge.evidence[data-check='handout']")
    expect(badge).to_have_count(1)
    desk = teacher.locator("#class-table a[href^='/review/sessions/']", has_text="Li Si")
    desk_url = server.url + desk.get_attribute("href")
    for language, width, _words in in_each_language_and_width(teacher, server.url):
        title, sentence = WORDS[language]
        teacher.goto(desk_url)
        card = teacher.locator("#data-evidence")
        expect(card.locator("h2")).to_have_text(title)
        expect(card.locator("li[data-check='handout']")).to_contain_text(sentence)
        expect(card.locator("li[data-check='handout']")).to_contain_text("A1")
        # the part's readings drawn beside a draw of the station's gyro
        chart = card.locator(".chart[data-figure='evidence-heading']")
        expect_chart_drawn(chart)
        expect(chart.locator(".xtick")).not_to_have_count(0)
        assert not teacher.evaluate(
            "() => document.documentElement.scrollWidth > window.innerWidth + 1"
        ), f"{language} at {width} px"

    # marked as seen with a note: the finding stays, with who looked and what they noted
    finding = teacher.locator("#data-evidence li[data-check='handout']")
    finding.locator("input[name=note]").fill("已与学生沟通 talked with them")
    with teacher.expect_navigation():
        finding.locator("button[type=submit]").click()
    finding = teacher.locator("#data-evidence li[data-check='handout']")
    expect(finding).to_have_class("seen")
    expect(finding.locator(".seen-note")).to_contain_text("talked with them")
