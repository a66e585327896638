"""Issue 34: a refused form comes back with everything typed, every refused field marked
beside it in the reader's language, and the focus (and the view) on the first one -- in a
real browser at a phone's and a laptop's width, in English and Chinese."""

from __future__ import annotations

from pathlib import Path

import pytest
from playwright.sync_api import expect

from app.cli.demo import DEMO_ASSIGNMENT
from tests.e2e.conftest import log_in
from tests.factories import pdf_text

pytestmark = pytest.mark.e2e

WIDTHS = (390, 1366)
LANGUAGES = {  # language: words the refusal must show
    "en": {
        "latitude": "The latitude must be between −90° and 90°.",
        "rate": "The Earth rate must be a positive number of °/h.",
        "number": "Type a number from -90 to 90.",
        "tolerance": "Type a number from 0 to 180.",
    },
    "zh-CN": {
        "latitude": "纬度必须在 −90° 到 90° 之间。",
        "rate": "地球自转角速度必须是正数（°/h）。",
        "number": "请输入 -90 到 90 之间的数。",
        "tolerance": "请输入 0 到 180 之间的数。",
    },
}


def expect_focus_on(page, name: str, where: str = "") -> None:
    """The field named ``name`` has the focus -- waited for: the browser applies
    ``autofocus`` at its next rendering update, which may come after the page's load
    event (an immediate check failed a fresh-clone run once)."""
    expect(page.locator(":focus"), where or None).to_have_attribute("name", name)


def in_view(page, selector: str) -> bool:
    """Whether the element is inside the window as the page opens (no scrolling needed)."""
    box = page.locator(selector).bounding_box()
    size = page.viewport_size
    return box is not None and box["y"] >= 0 and box["y"] + box["height"] <= size["height"]


def in_each_language_and_width(page, url: str):
    """(language, width, words) for every language and width, the page switched to them
    (the language chosen as a reader does, with the language switch's cookie)."""
    for language, words in LANGUAGES.items():
        page.context.add_cookies([{"name": "gyrolab_lang", "value": language, "url": url}])
        for width in WIDTHS:
            page.set_viewport_size({"width": width, "height": 844})
            yield language, width, words


def test_a_refused_practice_session_keeps_what_the_student_typed(demo_server, new_page):
    server, credentials = demo_server
    page = new_page()
    log_in(page, server.url, "student2", credentials["student2"])
    for _language, width, words in in_each_language_and_width(page, server.url):
        page.goto(f"{server.url}/lab")
        form = page.locator("#new-session")
        form.locator("input[name=title]").fill(f"Roof lab {width}")
        form.locator("select[name=station]").select_option("custom")
        form.locator("input[name=latitude_deg]").fill("91")
        form.locator("input[name=earth_rate_deg_h]").fill("0")
        form.locator("input[name=rotation][value=cw]").check()
        form.locator("input[name=heading_start_deg]").fill("12,5")
        form.locator("select[name=preset]").select_option("navigation-fog")
        with page.expect_navigation():
            form.locator("button[type=submit]").click()
        form = page.locator("#new-session")
        expect(form.locator("input[name=title]")).to_have_value(f"Roof lab {width}")
        expect(form.locator("select[name=station]")).to_have_value("custom")
        expect(form.locator("input[name=latitude_deg]")).to_have_value("91")
        expect(form.locator("input[name=earth_rate_deg_h]")).to_have_value("0")
        expect(form.locator("input[name=rotation][value=cw]")).to_be_checked()
        expect(form.locator("input[name=heading_start_deg]")).to_have_value("12,5")
        expect(form.locator("select[name=preset]")).to_have_value("navigation-fog")
        expect(form.locator("#error-latitude_deg")).to_have_text(words["latitude"])
        expect(form.locator("#error-earth_rate_deg_h")).to_have_text(words["rate"])
        expect_focus_on(page, "latitude_deg")
        assert in_view(page, "#error-latitude_deg"), f"the message is off screen at {width} px"


def test_a_refused_assignment_shows_every_problem_beside_its_field(demo_server, new_page):
    server, credentials = demo_server
    page = new_page()
    log_in(page, server.url, "teacher", credentials["teacher"])
    page.goto(f"{server.url}/courses")
    page.locator("a[href^='/courses/']").first.click()
    course_url = page.url
    for _language, width, words in in_each_language_and_width(page, server.url):
        page.goto(course_url)
        form = page.locator("#new-assignment")
        form.locator("input[name=title]").fill(f"Week 3 ({width})")
        form.locator("input[name=latitude_deg]").fill("north")
        form.locator("summary", has_text="").last.click()  # the advanced settings
        form.locator("input[name=tolerance_heading_deg]").fill("-1")
        with page.expect_navigation():
            form.locator("button[type=submit]").click()
        form = page.locator("#new-assignment")
        expect(form.locator("input[name=title]")).to_have_value(f"Week 3 ({width})")
        expect(form.locator("input[name=latitude_deg]")).to_have_value("north")
        expect(form.locator("input[name=tolerance_heading_deg]")).to_have_value("-1")
        expect(form.locator("#error-latitude_deg")).to_have_text(words["number"])
        # the folded section holding a refused field is open, its message visible
        expect(form.locator("#error-tolerance_heading_deg")).to_have_text(words["tolerance"])
        expect(form.locator("#error-tolerance_heading_deg")).to_be_visible()
        expect(form.locator(".form-problems li")).to_have_count(2)
        expect_focus_on(page, "latitude_deg")
        assert in_view(page, "#error-latitude_deg"), f"the message is off screen at {width} px"


def test_a_released_grade_is_amended_and_the_student_sees_why(demo_server, new_page):
    """A teacher (English, a laptop) corrects a released grade; the student (Chinese, a
    phone) sees the new grade, the old one and the reason."""
    server, credentials = demo_server
    teacher = new_page("en-US")
    teacher.set_viewport_size({"width": 1366, "height": 900})
    log_in(teacher, server.url, "teacher", credentials["teacher"])
    teacher.get_by_role("link", name="Demo: FOG north-finding lab 光纤陀螺寻北实验").click()
    teacher.locator("#assignments a", has_text="Four-position north finding").first.click()
    teacher.locator("#class-table tr[data-username='student2'] a").click()
    desk = teacher.url
    teacher.fill("input[name=points]", "80")
    teacher.once("dialog", lambda dialog: dialog.accept())
    with teacher.expect_navigation():
        teacher.locator("#release-button").click()
    expect(teacher.locator("#session-status")).to_have_text("graded")
    teacher.fill("input[name=points]", "85")
    with teacher.expect_navigation():  # no reason: refused, the points typed are kept
        teacher.locator("#amend-button").click()
    expect(teacher.locator("#review-error")).to_contain_text("Say why the grade changes")
    expect(teacher.locator("input[name=points]")).to_have_value("85")
    expect_focus_on(teacher, "reason")
    teacher.fill("textarea[name=reason]", "Part B was marked against the wrong latitude.")
    with teacher.expect_navigation():
        teacher.locator("#amend-button").click()
    assert teacher.url.startswith(desk)
    expect(teacher.locator("#grade-history")).to_contain_text("80 → 85")

    student = new_page("zh-CN")
    student.set_viewport_size({"width": 390, "height": 844})
    log_in(student, server.url, "student2", credentials["student2"])
    student.goto(f"{server.url}/lab")
    student.locator("#sessions a", has_text=DEMO_ASSIGNMENT).first.click()
    expect(student.locator("#grade")).to_have_text("85 / 100")
    history = student.locator("#grade-history")
    expect(history).to_contain_text("成绩更改记录")
    expect(history).to_contain_text("80 → 85")
    expect(history).to_contain_text("Part B was marked against the wrong latitude.")
    box = history.bounding_box()
    assert box is not None and box["x"] >= 0 and box["x"] + box["width"] <= 390
    # the graded work's report is the graded attempt's: its grade, not "current data"
    with student.expect_download() as download:
        student.locator("#report-link").click()
    assert "attempt-1" in download.value.suggested_filename
    text = " ".join(pdf_text(Path(download.value.path()).read_bytes()).split())
    assert "第 1 次提交" in text and "85 / 100" in text


OTHER_FORMS = {  # language: the refusals of the roster, token and password forms
    "en": (
        "is not a valid username",
        "Every token needs at least the read scope.",
        "The current password is wrong.",
    ),
    "zh-CN": ("不是有效的用户名", "令牌至少需要“读取”权限。", "当前密码不正确。"),
}


def test_the_roster_token_and_password_forms_keep_what_was_typed(demo_server, new_page):
    server, credentials = demo_server
    page = new_page()
    log_in(page, server.url, "teacher", credentials["teacher"])
    for language, width, _words in in_each_language_and_width(page, server.url):
        username_word, scope_word, password_word = OTHER_FORMS[language]
        where = f"{language} at {width} px"

        page.goto(f"{server.url}/courses/1")
        form = page.locator("#add-student")
        form.locator("input[name=username]").fill("wang wu")
        form.locator("input[name=display_name]").fill("王五")
        form.locator("input[name=email]").fill("wang@example.org")
        with page.expect_navigation():
            form.locator("button[type=submit]").click()
        form = page.locator("#add-student")
        expect(form.locator("input[name=display_name]")).to_have_value("王五")
        expect(form.locator("input[name=email]")).to_have_value("wang@example.org")
        expect(form.locator("#error-username")).to_contain_text(username_word)
        expect_focus_on(page, "username", where)
        assert in_view(page, "#field-username"), where

        page.goto(f"{server.url}/account/tokens")
        form = page.locator("#token-form")
        form.locator("input[name=name]").fill("bench PC")
        form.locator("input[value=read]").uncheck()
        with page.expect_navigation():
            form.locator("button[type=submit]").click()
        form = page.locator("#token-form")
        expect(form.locator("input[name=name]")).to_have_value("bench PC")
        expect(form.locator("input[value=upload]")).to_be_checked()
        expect(form.locator("input[value=read]")).not_to_be_checked()
        expect(form.locator("#error-scopes")).to_have_text(scope_word)
        expect_focus_on(page, "scopes", where)

        page.goto(f"{server.url}/account/password")
        form = page.locator("#password-form")
        form.locator("input[name=current_password]").fill("not-my-password")
        form.locator("input[name=new_password]").fill("a-new-password-1")
        form.locator("input[name=confirm_password]").fill("a-new-password-1")
        with page.expect_navigation():
            form.locator("button[type=submit]").click()
        expect(page.locator("#error-current_password")).to_have_text(password_word)
        expect_focus_on(page, "current_password", where)
