"""Issue 34 item 7: the teacher's class table, downloaded from the dashboard in a real
browser (a laptop in English, a phone in Chinese), names lab partners and has the
feedback and position-comment columns in the teacher's language (their contents:
tests/test_class_exports.py)."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from tests.e2e.conftest import log_in

pytestmark = pytest.mark.e2e

HEADERS = {
    "en": ("Lab partners", "Feedback", "Comments on positions"),
    "zh-CN": ("实验搭档", "反馈", "各位置的批注"),
}


@pytest.mark.parametrize(("language", "width"), [("en", 1366), ("zh-CN", 390)])
def test_the_class_table_download_names_partners_and_the_review(
    demo_server, new_page, language, width
):
    server, credentials = demo_server
    page = new_page()
    page.context.add_cookies([{"name": "gyrolab_lang", "value": language, "url": server.url}])
    page.set_viewport_size({"width": width, "height": 844})
    log_in(page, server.url, "teacher", credentials["teacher"])
    page.goto(f"{server.url}/courses/1/assignments/1")
    button = page.locator("#export-csv")
    box = button.bounding_box()
    assert box["x"] >= 0 and box["x"] + box["width"] <= width
    with page.expect_download() as download:
        button.click()
    text = Path(download.value.path()).read_text(encoding="utf-8-sig")
    rows = list(csv.reader(text.splitlines()))
    for header in HEADERS[language]:
        assert header in rows[0], rows[0]
    assert {"student1", "student2", "student3"} <= {row[0] for row in rows[1:]}
    assert all(len(row) == len(rows[0]) for row in rows)
