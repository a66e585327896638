"""Issue 35 item 3 in a real browser: the student reads the accuracy planner before
recording, and the teacher reads the class's scatter against it, at 390 and 1366 px in
English and Chinese; nothing leaves the screen sideways."""

from __future__ import annotations

import pytest
from playwright.sync_api import expect

from app.cli.demo import DEMO_ASSIGNMENT
from tests.e2e.conftest import log_in
from tests.e2e.test_forms_flow import in_each_language_and_width

pytestmark = pytest.mark.e2e

SENTENCE = {"en": "With 60 s per position expect ±", "zh-CN": "每个位置记录 60 秒，预期航向 ±"}
PAGE_WIDER_THAN_WINDOW = "() => document.documentElement.scrollWidth > window.innerWidth + 1"


def test_the_planner_for_the_student_and_the_class_against_it_for_the_teacher(
    demo_server, new_page
):
    server, credentials = demo_server
    student = new_page()
    log_in(student, server.url, "student1", credentials["student1"])
    teacher = new_page()
    log_in(teacher, server.url, "teacher", credentials["teacher"])
    for language, width, _words in in_each_language_and_width(student, server.url):
        where = f"{language} at {width} px"
        student.goto(f"{server.url}/lab")
        demo = student.locator("#sessions a[href^='/lab/sessions/']", has_text=DEMO_ASSIGNMENT)
        demo.first.click()  # not a newer session another test may have given student1
        plan = student.locator("#accuracy-plan")
        expect(plan.locator(".plan-sentence")).to_contain_text(SENTENCE[language])
        plan.locator("summary").click()
        expect(plan.locator("#plan-table tbody tr")).to_have_count(11)
        expect(plan.locator("#plan-table .badge")).to_have_count(2)  # the best of each order
        assert not student.evaluate(PAGE_WIDER_THAN_WINDOW), where

        teacher.context.add_cookies(
            [{"name": "gyrolab_lang", "value": language, "url": server.url}]
        )
        teacher.set_viewport_size({"width": width, "height": 844})
        teacher.goto(f"{server.url}/courses/1/assignments/1")
        card = teacher.locator("#class-accuracy")
        card.scroll_into_view_if_needed()
        expect(card.locator("tr[data-quantity]")).to_have_count(3)
        expect(card.locator("tr[data-quantity='heading'] .badge")).to_be_visible()
        box = card.locator("tr[data-quantity='heading'] .badge").bounding_box()
        assert box["x"] + box["width"] <= width, where  # the verdict is on screen
        assert not teacher.evaluate(PAGE_WIDER_THAN_WINDOW), where
