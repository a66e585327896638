"""A teacher imports a roster in a real browser; an imported student must change password."""

from __future__ import annotations

import csv

import openpyxl
import pytest
from playwright.sync_api import expect

from tests.e2e.conftest import TEACHER_PASSWORD, axe_problems

pytestmark = pytest.mark.e2e


def log_in(page, url, username, password):
    page.goto(f"{url}/login")
    page.fill("input[name=username]", username)
    page.fill("input[name=password]", password)
    page.click("button[type=submit].primary")


def test_teacher_imports_roster_and_student_changes_password(live_server, new_page, tmp_path):
    url = live_server.url
    teacher = new_page()
    log_in(teacher, url, "teacher", TEACHER_PASSWORD)
    expect(teacher.locator("h1")).to_contain_text("E2E Teacher")

    teacher.fill("input[name=name]", "惯性导航实验 1 班")
    teacher.get_by_role("button", name="Create course").click()
    expect(teacher.locator("h1")).to_contain_text("惯性导航实验 1 班")

    roster = tmp_path / "roster.csv"
    roster.write_text(
        "学号,姓名,邮箱\n2024001,张三,\n2024002,李四,li@example.edu\n", encoding="utf-8-sig"
    )
    teacher.set_input_files("input[name=roster_file]", str(roster))
    teacher.get_by_role("button", name="Import", exact=True).click()
    expect(teacher.locator("#credentials")).to_contain_text("张三")
    assert axe_problems(teacher) == []  # the one-time passwords page
    with teacher.expect_download() as download_info:
        teacher.click("#download-credentials")
    saved = tmp_path / "passwords.csv"
    download_info.value.save_as(saved)
    rows = list(csv.reader(saved.open(encoding="utf-8-sig")))
    assert rows[0] == ["Username / student number", "Name", "Initial password"]  # the page's
    passwords = {username: (name, password) for username, name, password in rows[1:]}
    assert passwords["2024001"][0] == "张三"
    password = passwords["2024001"][1]
    assert download_info.value.suggested_filename == "惯性导航实验-1-班_initial-passwords.csv"
    with teacher.expect_download() as download_info:  # the same, for Excel: numbers as text
        teacher.click("#download-credentials-xlsx")
    assert download_info.value.suggested_filename.endswith("_initial-passwords.xlsx")
    download_info.value.save_as(tmp_path / "passwords.xlsx")
    sheet = openpyxl.load_workbook(tmp_path / "passwords.xlsx").worksheets[0]
    cells = list(sheet.iter_rows(values_only=True))
    assert cells[0] == ("Username / student number", "Name", "Initial password")
    assert ("2024001", "张三", password) in cells

    student = new_page(locale="zh-CN")
    log_in(student, url, "2024001", password)
    expect(student).to_have_url(f"{url}/account/password")
    expect(student.locator(".flash-warning")).to_contain_text("初始密码")
    student.goto(f"{url}/")  # cannot skip the change
    expect(student).to_have_url(f"{url}/account/password")
    student.fill("input[name=current_password]", password)
    student.fill("input[name=new_password]", "my-new-secret-1")
    student.fill("input[name=confirm_password]", "my-new-secret-1")
    student.click("button[type=submit].primary")
    expect(student).to_have_url(f"{url}/")
    expect(student.locator("main")).to_contain_text("惯性导航实验 1 班")
    expect(student.locator(".flash-success")).to_be_visible()


def test_logout_then_replayed_cookie_gets_login_page(live_server, new_page):
    page = new_page()
    log_in(page, live_server.url, "teacher", TEACHER_PASSWORD)
    expect(page.locator("h1")).to_contain_text("E2E Teacher")
    cookies = page.context.cookies()
    page.click("text=Log out")
    expect(page).to_have_url(f"{live_server.url}/login")
    page.context.add_cookies(cookies)
    page.goto(f"{live_server.url}/")
    expect(page).to_have_url(f"{live_server.url}/login?next=/")


def test_api_reference_renders_under_the_csp(live_server, new_page):
    page = new_page()
    page.goto(f"{live_server.url}/docs")
    expect(page.locator(".opblock-summary-path").first).to_be_visible()
    expect(page.locator("#swagger-ui")).to_contain_text("/api/v1/sessions")
