"""The typed grid reads a pasted block as the server reads the same text as a file
(``app.core.readings.parse_readings_csv``): the page's reader is JavaScript, the file's is
Python, and where they differed a student's paste was laid out wrongly -- a table with one
row per position across the rows, a logger's times as position 1 -- and called "all
valid".  Each of the layouts below, built from the handout's part A, must give the same
readings both ways."""

from __future__ import annotations

import pytest
from playwright.sync_api import expect

from app.core.readings import parse_readings_csv
from tests.e2e.conftest import STUDENT_PASSWORD, log_in
from tests.e2e.test_lab_flow import paste, start_practice, table

pytestmark = pytest.mark.e2e

ROWS = table("handout_horizontal.csv")
COLUMNS = [[row[k] for row in ROWS] for k in range(4)]
MEANS = [sum(float(v) for v in column) / len(column) for column in COLUMNS]
TAB = "\t"
PLAIN = "\n".join(TAB.join(row) for row in ROWS)
NAMES = "位置1\t位置2\t位置3\t位置4\n"

LAYOUTS = {
    "no header": PLAIN,
    "named positions": NAMES + PLAIN,
    "row numbers": "序号\tP1\tP2\tP3\tP4\n"
    + "\n".join(f"{i}\t{TAB.join(r)}" for i, r in enumerate(ROWS, 1)),
    "the turntable's angles": "0°\t-90°\t-180°\t-270°\n" + PLAIN,
    "the handout as printed": "位置\t1\t2\t3\t4\n"
    + "\n".join(("采样值" if i == 4 else "") + TAB + TAB.join(r) for i, r in enumerate(ROWS))
    + "\n平均值\t"
    + TAB.join(f"{m:.2f}" for m in MEANS),
    "an unlabelled AVERAGE row": NAMES + PLAIN + "\n" + TAB.join(f"{m:.4f}" for m in MEANS),
    "one reading per row": "位置\t读数\n"
    + "\n".join(f"{k + 1}\t{v}" for k, column in enumerate(COLUMNS) for v in column),
    "one row per position": "\n".join(f"位置{k + 1}\t{TAB.join(c)}" for k, c in enumerate(COLUMNS)),
    "one row per position, numbered, with means": "位置\t"
    + TAB.join(str(i) for i in range(1, 11))
    + "\t平均值\n"
    + "\n".join(f"位置{k + 1}\t{TAB.join(c)}\t{MEANS[k]:.3f}" for k, c in enumerate(COLUMNS)),
    "notes typed": "\n".join(f"位置{k + 1}：{' '.join(c)}" for k, c in enumerate(COLUMNS)),
    "lines above the table": "陀螺寻北实验数据\n姓名：张三\t学号：2023001\n" + NAMES + PLAIN,
    "a row of units": NAMES + "°/h\t°/h\t°/h\t°/h\n" + PLAIN,
    "semicolons, decimal commas": "\n".join(";".join(c.replace(".", ",") for c in r) for r in ROWS),
    "spaces": "\n".join("  ".join(r) for r in ROWS),
    "a Chinese input method's commas": "\n".join("，".join(r) for r in ROWS),
    "a time column before the positions": "时间(s)\t"
    + NAMES.replace("\n", "")
    + "\n"
    + "\n".join(f"{0.1 * i:.1f}\t{TAB.join(r)}" for i, r in enumerate(ROWS)),
    "mean and σ rows beside a label column": "\t"
    + NAMES
    + "\n".join(f"{i}\t{TAB.join(r)}" for i, r in enumerate(ROWS, 1))
    + "\n平均值\t"
    + TAB.join(f"{m:.3f}" for m in MEANS)
    + "\n标准差\t0.1\t0.1\t0.1\t0.1",
    "both parts under their titles": "表1 水平面内\n"
    + NAMES
    + PLAIN
    + "\n表2 竖直面内\n"
    + NAMES
    + PLAIN,
    "the handout's ω1 … ω4 beside a time": "时间(s)\tω1\tω2\tω3\tω4\n"
    + "\n".join(f"{0.1 * i:.1f}\t{TAB.join(r)}" for i, r in enumerate(ROWS)),
    "a cell left empty": NAMES
    + "\n".join(TAB.join(r[:3] + [""] if i == 2 else r) for i, r in enumerate(ROWS)),
}


def test_the_grid_reads_each_layout_as_a_file_of_it_is_read(live_server, new_page):
    page = new_page()
    log_in(page, live_server.url, "student", STUDENT_PASSWORD)
    start_practice(page, live_server.url)
    grid = "#part-heading .readings-grid tbody"
    status = page.locator("#part-heading .grid-status")
    for name, text in LAYOUTS.items():
        page.locator("#part-heading .clear-grid").click()
        paste(page, f"{grid} input", text)
        expect(status).to_contain_text("all valid")
        cells = page.evaluate(
            """(grid) => [...document.querySelectorAll(grid + ' tr')].map(
                (tr) => [...tr.querySelectorAll('input')].map((input) => input.value))""",
            grid,
        )
        pasted = [[float(row[k].replace(",", ".")) for row in cells if row[k]] for k in range(4)]
        read = parse_readings_csv(text, part="heading").positions
        assert pasted == [list(column) for column in read], name


SYMMETRIC = [f"位置{k}" for k in (1, 2, 3, 4, 4, 3, 2, 1)]
VISITS = [COLUMNS[k % 4] for k in range(8)]  # eight columns of readings, as recorded
SYMMETRIC_LAYOUTS = {
    "each position named again on its second visit": TAB.join(SYMMETRIC)
    + "\n"
    + "\n".join(TAB.join(column[i] for column in VISITS) for i in range(10)),
    "the handout's numbering there and back": "位置\t1\t2\t3\t4\t4\t3\t2\t1\n"
    + "\n".join(TAB + TAB.join(column[i] for column in VISITS) for i in range(10)),
    "one row per visit": "\n".join(
        f"{name}\t{TAB.join(column)}" for name, column in zip(SYMMETRIC, VISITS, strict=True)
    ),
}


def test_the_symmetric_orders_second_visits_are_positions_five_to_eight(live_server, new_page):
    """1-2-3-4-4-3-2-1 with each position named again ("位置4" twice): refused as a
    position named twice by the file's reader, the rows of it laid wrongly by the grid's;
    both now read the second visits as positions 5-8, as the session numbers them."""
    page = new_page()
    log_in(page, live_server.url, "student", STUDENT_PASSWORD)
    start_practice(page, live_server.url)
    with page.expect_navigation():
        page.locator("#order-toggle").click()
    grid = "#part-heading .readings-grid tbody"
    for name, text in SYMMETRIC_LAYOUTS.items():
        page.locator("#part-heading .clear-grid").click()
        paste(page, f"{grid} input", text)
        expect(page.locator("#part-heading .grid-status")).to_contain_text("80 readings")
        cells = page.evaluate(
            """(grid) => [...document.querySelectorAll(grid + ' tr')].map(
                (tr) => [...tr.querySelectorAll('input')].map((input) => input.value))""",
            grid,
        )
        pasted = [[float(row[k]) for row in cells if row[k]] for k in range(8)]
        read = parse_readings_csv(text, part="heading").positions
        assert (
            pasted
            == [list(column) for column in read]
            == [[float(v) for v in column] for column in VISITS]
        ), name
