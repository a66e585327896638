"""The class board (issue 35, item 2): the pooled estimate against closed forms, and the
board's page, JSON, snapshot and API on a class that hands in."""

from __future__ import annotations

import html
import math

import pytest

from app.review.board import pooled
from tests.factories import (
    API,
    browser,
    do_lab,
    post_form,
    start,
    submit,
    token_for,
)


def test_the_pooled_value_is_the_inverse_variance_mean_widened_by_the_birge_ratio():
    # two groups: 15.0 ± 0.1 and 15.2 ± 0.2 → w = 100, 25; mean = (1500 + 380)/125 = 15.04
    result = pooled([15.0, 15.2], [0.1, 0.2])
    assert result.value == pytest.approx(15.04)
    chi2 = 100 * 0.04**2 + 25 * 0.16**2  # 0.8: less scatter than the σ say, no widening
    assert result.birge == 1.0 and chi2 < 1
    assert result.standard_error == pytest.approx(1 / math.sqrt(125))
    # far apart: χ² = 100·0.8² + 100·0.8² = 128 with 1 dof → the error widened √128 times
    wide = pooled([14.2, 15.8], [0.1, 0.1])
    assert wide.birge == pytest.approx(math.sqrt(128))
    assert wide.standard_error == pytest.approx(math.sqrt(128) / math.sqrt(200))
    assert pooled([None, math.nan], [0.1, 0.1]) is None


def test_the_board_pools_the_class_and_names_nobody_unless_asked(world):
    for name in ("s1", "s2", "s3"):
        student = browser(world, name)
        session_id = start(student, world)
        do_lab(student, session_id)
        if name != "s3":
            submit(student, session_id)  # s3 is still recording: on the board all the same
    teacher = browser(world, "teacher1")
    base = f"/courses/{world['course']}/assignments/{world['assignment']}/board"
    page = html.unescape(teacher.get(base).text)
    assert "The class measures the Earth" in page and "Groups with results: 3" in page
    assert "Earth rate 15.133 ± " in page  # the handout's 15.133 °/h, three times
    assert ">s1<" not in page and "s1+" not in page  # the groups' labels are numbers
    assert "Group 1" in page
    named = html.unescape(teacher.get(f"{base}?names=true").text)
    assert ">s1<" in named or "s1 " in named

    live = teacher.get(f"{base}.json").json()
    assert live["board"]["earth_rate"]["groups"] == 3
    assert live["board"]["earth_rate"]["value"] == pytest.approx(15.133, abs=5e-4)
    assert set(live["figures"]) == {"board-rate", "board-latitude", "board-heading"}
    assert [g["submitted"] for g in live["board"]["groups"]].count(False) == 1

    kept = post_form(teacher, f"{base}/snapshots", page=base)
    assert kept.status_code == 303
    snapshot = html.unescape(teacher.get(kept.headers["location"]).text)
    assert "Snapshot of" in snapshot and "Earth rate 15.133" in snapshot
    assert "Snapshots" in html.unescape(teacher.get(base).text)

    auth = token_for(teacher, "teacher1")
    board = teacher.get(f"{API}/assignments/{world['assignment']}/board", headers=auth).json()
    assert board["latitude"]["groups"] == 3 and board["names_shown"] is False
    assert all(group["label"] is None for group in board["groups"])

    chinese = teacher.get(base, headers={"Accept-Language": "zh-CN"}).text
    assert "全班共同测量地球" in chinese and "地球自转角速度 15.133" in chinese


def test_a_group_with_only_the_heading_part_is_on_the_board(world):
    from tests.factories import HEADING, save_manual

    student = browser(world, "s1")
    session_id = start(student, world)
    assert save_manual(student, session_id, "heading", HEADING).status_code == 200
    teacher = browser(world, "teacher1")
    base = f"/courses/{world['course']}/assignments/{world['assignment']}/board"
    page = teacher.get(base)
    assert page.status_code == 200 and "Groups with results: 1" in page.text
    group = teacher.get(f"{base}.json").json()["board"]["groups"][0]
    assert group["earth_rate_deg_h"] is None and group["heading_error_deg"] is not None
