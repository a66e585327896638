"""A teacher reviews the demo class in a real browser; the student revises and resubmits."""

from __future__ import annotations

import re

import pytest
from playwright.sync_api import expect

from tests.e2e.conftest import expect_chart_drawn, log_in

pytestmark = pytest.mark.e2e


def test_teacher_reviews_returns_and_student_resubmits(demo_server, new_page):
    server, credentials = demo_server
    teacher = new_page()
    log_in(teacher, server.url, "teacher", credentials["teacher"])
    teacher.get_by_role("link", name="Demo: FOG north-finding lab 光纤陀螺寻北实验").click()
    teacher.locator("#assignments a", has_text="Four-position north finding").first.click()
    # 2 submitted in the demo (1 when the amendment test released student2 first)
    expect(teacher.locator(".status-filter")).to_contain_text(re.compile(r"submitted [12]"))
    expect_chart_drawn(teacher.locator(".chart[data-figure='class-errors']"))
    teacher.locator("#class-table th", has_text="Az. error").click()  # sortable
    expect(teacher.locator("#class-table th[aria-sort]")).to_have_count(1)

    teacher.locator("#class-table tr[data-username='student1'] a").click()
    expect(teacher.locator("#truth")).to_contain_text("True azimuth of position 1")
    expect(teacher.locator("#auto-check")).to_contain_text("Heading")
    teacher.fill("textarea[name=feedback]", "Redo position 1 of part A with a longer dwell.")
    teacher.locator("summary", has_text="Comments on single positions").click()
    teacher.fill("input[name='comment-heading-1']", "Too short: use at least 20 s.")
    with teacher.expect_navigation():
        teacher.locator("#return-button").click()
    expect(teacher.locator("#session-status")).to_have_text("returned for revision")

    student = new_page()
    log_in(student, server.url, "student1", credentials["student1"])
    expect(student.locator("#my-work")).to_contain_text("returned for revision")
    student.locator("#my-work a", has_text="Four-position north finding").first.click()
    student.wait_for_load_state("load")
    expect(student.locator("#overall-feedback")).to_contain_text("longer dwell")
    expect(student.locator(".position-comment")).to_contain_text("Too short")
    section = student.locator("#part-heading")
    section.locator(".method-tab[data-method=simulator]").click()
    section.locator(".step[data-position='1']").click()
    if section.locator(".turn").is_enabled():
        section.locator(".turn").click()
    section.locator(".dwell").fill("120")  # 12 readings of the teaching gyro
    section.locator(".speed").select_option("60")
    section.locator(".start-sim").click()
    expect(section.locator(".trim-box")).to_be_visible(timeout=20_000)
    with student.expect_navigation():
        section.locator(".keep-all").click()
    # halfway through the fix (in progress again) the teacher's comments are still there
    expect(student.locator("#revising-notice")).to_be_visible()
    expect(student.locator("#overall-feedback")).to_contain_text("longer dwell")
    expect(student.locator(".position-comment")).to_contain_text("Too short")
    student.once("dialog", lambda dialog: dialog.accept())
    with student.expect_navigation():
        student.locator("#submit-session").click()
    expect(student.locator("#session-status")).to_have_text("submitted")

    teacher.reload()
    expect(teacher.locator("#attempts")).to_contain_text("Attempt 2")
    teacher.fill("input[name=points]", "92")
    with teacher.expect_navigation():
        teacher.locator("#release-button").click()
    expect(teacher.locator("#session-status")).to_have_text("graded")
    student.goto(f"{server.url}/")
    demo_row = student.locator("#my-work tr", has_text="Four-position north finding")
    expect(demo_row.locator(".grade")).to_contain_text("92 / 100")
    expect(student.locator("#notices")).to_contain_text("attempt 2 graded")
