"""GyroLab inside an LMS, in a real browser: ``gyrolab serve`` registered with a real LTI
1.3 platform on loopback (tests/lti_platform.py) by ``gyrolab lti add-platform``; Chromium
adds the activity by deep linking (GyroLab's answer auto-posts back to the LMS under
GyroLab's CSP), then a student's first launch lands in their session."""

from __future__ import annotations

import pytest
from playwright.sync_api import expect

from tests.e2e.conftest import axe_problems, running_server
from tests.lti_platform import (
    PlatformState,
    bound_socket,
    create_platform_app,
    register_with_cli,
    serving,
    url_of,
)

pytestmark = pytest.mark.e2e


def test_a_teacher_adds_gyrolab_and_a_student_lands_in_the_lab(tmp_path, new_page):
    with running_server(tmp_path, "--no-demo") as server:
        platform_socket = bound_socket()
        platform = PlatformState(url=url_of(platform_socket), tool_url=server.url)
        register_with_cli(server, platform)
        with serving(create_platform_app(platform), platform_socket):
            teacher = new_page(locale="zh-CN")
            teacher.goto(f"{platform.url}/start?user=teacher-1&kind=deep")
            expect(teacher.locator("h1")).to_have_text("添加 GyroLab 活动")
            assert axe_problems(teacher) == []  # the deep-linking picker, in Chinese
            teacher.fill("input[name=title]", "寻北实验")
            with teacher.expect_navigation(url=f"{platform.url}/deep-link-return"):
                teacher.click("text=新建并添加")
            expect(teacher.locator("body")).to_contain_text("added 1")
            assert platform.links["link-1"]["title"] == "寻北实验"

            student = new_page()
            student.goto(f"{platform.url}/start?user=student-1&link=link-1")
            student.wait_for_url(f"{server.url}/lab/sessions/*")
            expect(student.locator("header")).to_contain_text("Li Wei 李伟")
            expect(student.locator("h1")).to_contain_text("寻北实验")
