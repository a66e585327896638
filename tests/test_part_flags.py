"""The teacher's class table shows a part's flags as well as each position's: a submitted
attempt keeps its parts' flags (a wrong unit, a closure residual, a gyro still warming up),
so the row whose Earth-rate error is 99.97 % says why."""

from __future__ import annotations

import io
import json

import openpyxl
import pytest
from sqlmodel import select

from app.db import read_session
from app.models import Attempt
from app.review.service import part_flags
from tests.factories import HEADING, VERTICAL, browser, save_manual, start, submit

DEG_PER_S = 3600.0


def submitted_in_the_wrong_unit(world, username: str) -> int:
    """The handout's readings divided into °/s by the student's logger, saved as °/h."""
    student = browser(world, username)
    session_id = start(student, world)
    for part, table in (("heading", HEADING), ("latitude", VERTICAL)):
        columns = {k: [v / DEG_PER_S for v in values] for k, values in table.items()}
        assert save_manual(student, session_id, part, columns, unit="deg/h").status_code == 200
    submit(student, session_id)
    return session_id


def test_a_unit_slip_reaches_the_class_table_and_its_exports(world):
    session_id = submitted_in_the_wrong_unit(world, "s1")
    with read_session() as db:
        [attempt] = db.exec(select(Attempt).where(Attempt.session_id == session_id)).all()
        frozen = json.loads(attempt.results_json)
    keys = [flag["key"] for part in ("heading", "latitude") for flag in frozen[part]["flags"]]
    assert keys.count("flag.unit_slip") == 2  # each part's own, frozen with the attempt
    teacher = browser(world, "teacher1")
    base = f"/courses/{world['course']}/assignments/{world['assignment']}"
    page = teacher.get(base).text
    table = page[
        page.index('id="class-table"') : page.index("</table>", page.index('id="class-table"'))
    ]
    assert table.count(">unit?</span>") == 1  # once, though both parts say it
    assert "were they recorded in °/s and saved as °/h?" in table  # the badge's title
    rows = teacher.get(f"{base}/export.csv").content.decode("utf-8-sig").splitlines()
    header = rows[0].split(",")
    # in the reader's words (the handout's vertical table also fails closure: see below)
    assert rows[1].split(",")[header.index("Flags")].split(";") == ["closure", "unit?"]
    book = openpyxl.load_workbook(io.BytesIO(teacher.get(f"{base}/export.xlsx").content))
    sheet = book.worksheets[0]
    names = [cell.value for cell in sheet[1]]
    assert sheet.cell(2, names.index("Flags") + 1).value == "closure;unit?"
    teacher.cookies.set("gyrolab_lang", "zh-CN")
    assert ">单位？</span>" in teacher.get(base).text
    rows = teacher.get(f"{base}/export.csv").content.decode("utf-8-sig").splitlines()
    assert rows[1].split(",")[rows[0].split(",").index("标记")] == "单位？;闭合差"


def test_the_right_unit_is_not_flagged_and_an_old_attempt_has_no_part_flags(world):
    student = browser(world, "s2")
    session_id = start(student, world)
    for part, table in (("heading", HEADING), ("latitude", VERTICAL)):
        assert save_manual(student, session_id, part, table).status_code == 200
    submit(student, session_id)
    with read_session() as db:
        [attempt] = db.exec(select(Attempt).where(Attempt.session_id == session_id)).all()
        flags = part_flags(json.loads(attempt.results_json))
    # the handout's vertical table does not close (d = −0.285 °/h against σ_d = 0.027): the
    # lab page says so, and now the class table too; its unit is right
    assert [flag["key"] for flag in flags] == ["flag.closure"]
    # attempts frozen before results kept their flags have none to show
    assert part_flags({"heading": {"theta_deg": 1.0}, "latitude": None}) == []


@pytest.mark.parametrize(
    ("results", "keys"),
    [
        (
            {
                "heading": {"flags": [{"key": "flag.spikes", "params": {"position": 2, "n": 1}}]},
                "latitude": {
                    "flags": [{"key": "flag.closure", "params": {"d": "0.4", "sigma": "0.1"}}]
                },
            },
            ["flag.closure"],  # a position's flag comes from the current readings instead
        ),
        (
            {
                "heading": {
                    "flags": [{"key": "flag.warming_up", "params": {"minutes": 3, "moved": "0.8°"}}]
                },
                "latitude": {
                    "flags": [{"key": "flag.warming_up", "params": {"minutes": 3, "moved": "0.8°"}}]
                },
            },
            ["flag.warming_up"],
        ),
    ],
)
def test_part_flags_are_those_of_a_part_each_once(results, keys):
    assert [flag["key"] for flag in part_flags(results)] == keys
