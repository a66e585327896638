"""Single sign-on in a real browser: GyroLab served by uvicorn, a real OpenID provider on
loopback (oidc-provider-mock), Chromium clicking through both."""

from __future__ import annotations

import pytest
from oidc_provider_mock import run_server_in_thread
from playwright.sync_api import expect

from tests.e2e.conftest import running_server

pytestmark = pytest.mark.e2e


def test_a_student_signs_in_with_the_university_id(tmp_path, monkeypatch, new_page):
    with run_server_in_thread() as provider:
        url = f"http://localhost:{provider.server_port}/.well-known/openid-configuration"
        monkeypatch.setenv("GYROLAB_OIDC_DISCOVERY_URL", url)
        monkeypatch.setenv("GYROLAB_OIDC_CLIENT_ID", "gyrolab")
        monkeypatch.setenv("GYROLAB_OIDC_CLIENT_SECRET", "gyrolab-secret")
        monkeypatch.setenv("GYROLAB_OIDC_NAME", "Uni ID")
        with running_server(tmp_path, "--no-demo") as server:
            page = new_page(locale="zh-CN")
            page.goto(f"{server.url}/login?next=/lab")
            page.click("a.sso-button")  # "使用Uni ID登录"
            page.fill("input[name=sub]", "zhao.lei")  # the provider's own log-in form
            with page.expect_navigation(url=f"{server.url}/lab"):
                page.locator("form button").first.click()
            expect(page.locator("header")).to_contain_text("zhao.lei")
