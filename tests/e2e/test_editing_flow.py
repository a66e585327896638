"""Issue 34 item 5: a student's saved readings come back into the typed grid, a typo is
corrected in place, and only that position is saved again (a new take; the old one kept
in the history) -- in a real browser, at a phone's and a laptop's width, in both languages."""

from __future__ import annotations

import re

import pytest
from playwright.sync_api import expect

from tests.e2e.conftest import STUDENT_PASSWORD, log_in
from tests.e2e.test_lab_flow import paste, start_practice, table
from tests.factories import handout

pytestmark = pytest.mark.e2e

WORDS = {
    "en": {
        "loaded": "Your saved readings are in the grid",
        "unchanged": "Nothing changed",
        "download": "Download plot as a PNG",
        "typo": "-3,25",  # a decimal comma, as typed on a German keyboard
        "left": "-3,25",  # the cell as it shows once left (ASCII stays as typed)
    },
    "zh-CN": {
        "loaded": "表格中已载入已保存的读数",
        "unchanged": "没有改动",
        "download": "下载图表（PNG）",  # the chart toolbar speaks the page's language too
        "typo": "－３。２５",  # a Chinese input method's full-width forms and its "。"
        "left": "-3.25",  # shown as it will be saved once the cell is left
    },
}


@pytest.mark.parametrize(("language", "width"), [("en", 1366), ("zh-CN", 390)])
def test_saved_readings_come_back_and_one_typo_is_corrected(live_server, new_page, language, width):
    page = new_page()
    log_in(page, live_server.url, "student", STUDENT_PASSWORD)
    page.context.add_cookies([{"name": "gyrolab_lang", "value": language, "url": live_server.url}])
    page.set_viewport_size({"width": width, "height": 844})
    start_practice(page, live_server.url)
    rows = table("handout_horizontal.csv")
    cells = "#part-heading .readings-grid tbody input"
    paste(page, cells, "\n".join("\t".join(row) for row in rows))
    with page.expect_navigation():
        page.locator("#part-heading .save-manual").click()

    # after the reload the grid holds what was saved, every position, as typed
    grid = page.locator("#part-heading .readings-grid tbody tr")
    status = page.locator("#part-heading .grid-status")
    expect(status).to_contain_text(WORDS[language]["loaded"])
    for r in (0, 5, len(rows) - 1):
        for c in range(4):
            expect(grid.nth(r).locator("input").nth(c)).to_have_value(rows[r][c])

    page.locator("#part-heading .chart[data-figure]").first.scroll_into_view_if_needed()
    toolbar = page.locator("#part-heading .modebar-btn[data-title]").first
    expect(toolbar).to_have_attribute("data-title", WORDS[language]["download"])

    # choosing position 2 marks its column; one typo corrected there and saved
    page.locator("#part-heading .step[data-position='2']").click()
    expect(page.locator("#part-heading .readings-grid thead th").nth(2)).to_have_class(
        "column-selected"
    )
    typo = grid.nth(3).locator("input").nth(1)
    assert typo.is_visible()
    typo.fill(WORDS[language]["typo"])
    typo.press("Tab")
    expect(typo).to_have_value(WORDS[language]["left"])
    with page.expect_navigation():
        page.locator("#part-heading .save-manual").click()
    expect(grid.nth(3).locator("input").nth(1)).to_have_value("-3.25")
    expect(grid.nth(4).locator("input").nth(1)).to_have_value(rows[4][1])
    history = page.locator("#take-history tbody tr")
    expect(history).to_have_count(5)  # four takes, and position 2 taken again
    expect(page.locator("#take-history tbody tr.muted")).to_have_count(1)  # the old take

    # saving an unchanged grid stores nothing and says so
    page.locator("#part-heading .save-manual").click()
    expect(status).to_contain_text(WORDS[language]["unchanged"])
    expect(history).to_have_count(5)


def test_rows_added_by_a_long_paste_mark_the_chosen_column(live_server, new_page):
    """Rows a paste adds are made with the chosen position's column marked (not by walking
    the whole grid again: that made a 60,000-row paste take 28 s), and choosing another
    position moves the mark in them too."""
    page = new_page()
    log_in(page, live_server.url, "student", STUDENT_PASSWORD)
    start_practice(page, live_server.url)
    header = page.locator("#part-heading .readings-grid thead th")
    expect(header.nth(1)).to_have_class("column-selected")  # position 1, from the start
    paste(page, "#part-heading .readings-grid tbody input", "\n".join(["1\t2\t3\t4"] * 40))
    row = page.locator("#part-heading .readings-grid tbody tr").nth(34)
    expect(row.locator("td").nth(0)).to_have_class("column-selected")
    expect(row.locator("th")).to_have_text("35")
    expect(row.locator("input").nth(2)).to_have_attribute("aria-label", "Position 3 #35")
    page.locator("#part-heading .step[data-position='3']").click()
    expect(row.locator("td").nth(2)).to_have_class("column-selected")
    expect(row.locator("td").nth(0)).not_to_have_class("column-selected")


def test_a_pasted_table_with_a_row_of_units_under_its_names(live_server, new_page):
    """An instrument's export pasted with its names and a units row: both are passed over,
    as the server reads such a file (app.core.readings.is_units_row)."""
    page = new_page()
    log_in(page, live_server.url, "student", STUDENT_PASSWORD)
    start_practice(page, live_server.url)
    block = "序号\t位置1\t位置2\t位置3\t位置4\n单位：\t(°/h)\t(°/h)\t(°/h)\t(°/h)\n" + "\n".join(
        f"{k}\t10.74\t-0.50\t-11.20\t0.10" for k in range(1, 11)
    )  # the units row named as such in its first cell, under a row-number column's name
    paste(page, "#part-heading .readings-grid tbody input", block)
    first = page.locator("#part-heading .readings-grid tbody tr").first.locator("input")
    expect(first.nth(0)).to_have_value("10.74")
    expect(page.locator("#part-heading .readings-grid input.invalid")).to_have_count(0)
    expect(page.locator("#part-heading .grid-status")).to_contain_text("Pasted 10 rows")
    # The handout's table as printed -- "位置 | 1 | 2 | 3 | 4", a label column with "采样值"
    # and a last row of means -- pasted into the other part: the labels and the means are
    # passed over and said (app.core.table_headers reads a file the same way).
    printed = "位置\t1\t2\t3\t4\n" + "\n".join(
        [("采样值" if row == 4 else "") + "\t11.10\t9.77\t-11.76\t-9.99" for row in range(10)]
        + ["平均值\t11.13\t9.83\t-11.81\t-9.93"]
    )
    paste(page, "#part-latitude .readings-grid tbody input", printed)
    rows = page.locator("#part-latitude .readings-grid tbody tr")
    expect(rows.nth(4).locator("input").nth(0)).to_have_value("11.10")
    expect(rows.nth(9).locator("input").nth(3)).to_have_value("-9.99")
    expect(rows).to_have_count(10)  # ten rows of readings, none of means
    expect(page.locator("#part-latitude .readings-grid input.invalid")).to_have_count(0)
    status = page.locator("#part-latitude .grid-status")
    expect(status).to_contain_text("Pasted 10 rows")
    expect(status).to_contain_text("a row of means or another summary skipped")
    expect(status).to_contain_text("the columns before position 1 skipped")
    # typed with a Chinese input method: cells separated by 、, as the server reads a file
    paste(page, "#part-heading .readings-grid tbody input", "10.74、2.88、-9.11、-0.96\n" * 3)
    first = page.locator("#part-heading .readings-grid tbody tr").first.locator("input")
    expect(first.nth(3)).to_have_value("-0.96")
    expect(page.locator("#part-heading .grid-status")).to_contain_text("Pasted 3 rows")
    # A long table -- one reading per row beside its position -- pasted into any cell: each
    # position's readings go to its own column, not the positions' numbers to column 1; the
    # columns of positions not in the paste are left as they were.
    third = rows.nth(2).locator("input").nth(1)
    cell = "#part-latitude .readings-grid tbody tr:nth-child(3) input[data-column='2']"
    paste(page, cell, "位置\t读数 (°/h)\n3\t-11.50\n3\t-11.40\nP2\t9.60\n")
    first = rows.nth(0).locator("input")
    expect(first.nth(2)).to_have_value("-11.50")
    expect(rows.nth(1).locator("input").nth(2)).to_have_value("-11.40")
    expect(first.nth(1)).to_have_value("9.60")
    expect(first.nth(0)).to_have_value("11.10")  # position 1 untouched
    expect(third).to_have_value("9.77")
    expect(status).to_contain_text("each position's readings put in its own column")
    # A whole sheet copied: lines about the table above its header (a title, the name and
    # student number), and a spreadsheet's =AVERAGE row under the readings, without a
    # label, told by its decimals (app.core.means_row): both left out, as a file's are
    readings = [[10.74, -0.5, -11.2, 0.1], [10.65, -0.41, -11.3, 0.12], [10.8, -0.46, -11.25, 0.09]]
    means = [sum(column) / 3 for column in zip(*readings, strict=True)]
    block = "陀螺寻北实验\n姓名：张三\t学号：2023001\nP1\tP2\tP3\tP4\n" + "\n".join(
        "\t".join(f"{v:.2f}" for v in row) for row in readings
    )
    paste(
        page, "#part-heading .readings-grid tbody input", block + "\n" + "\t".join(map(str, means))
    )
    expect(page.locator("#part-heading .grid-status")).to_contain_text("a title, a name, a date")
    heading = page.locator("#part-heading .readings-grid tbody tr")
    expect(heading.nth(2).locator("input").nth(0)).to_have_value("10.80")
    expect(heading.nth(3).locator("input").nth(0)).to_have_value("10.74")  # the first paste's
    expect(page.locator("#part-heading .grid-status")).to_contain_text("AVERAGE row")
    expect(page.locator("#part-heading .grid-status")).to_contain_text("Pasted 3 rows")
    # both of the handout's tables pasted into part B's grid, each under its own title:
    # part B's table alone, from under its title (app.core.part_names reads a file so)
    from tests.test_table_headers import stacked

    both = stacked(
        "表 1 光纤陀螺在水平面内4个位置的采样值", "表 2 光纤陀螺在竖直面内4个位置的采样值", "\t"
    )
    paste(page, "#part-latitude .readings-grid tbody input", both)
    latitude = page.locator("#part-latitude .readings-grid tbody tr")
    vertical = handout("handout_vertical.csv")
    expect(latitude.nth(0).locator("input").nth(0)).to_have_value(f"{vertical[1][0]:.2f}")
    expect(latitude.nth(9).locator("input").nth(3)).to_have_value(f"{vertical[4][9]:.2f}")
    expect(latitude).to_have_count(10)  # ten rows of part B's readings: no header, no means
    expect(page.locator("#part-latitude .grid-status")).to_contain_text("this part's table taken")
    # under titles that name no part, the second table's header ends the paste: its
    # "位置 | 1 | 2 | 3 | 4" is never read as a row of readings
    paste(page, "#part-heading .readings-grid tbody input", stacked("Table 1", "Table 2", "\t"))
    grid = page.locator("#part-heading .readings-grid tbody tr")
    expect(grid.nth(9).locator("input").nth(0)).to_have_value("10.84")  # table 1's last
    expect(grid).to_have_count(10)
    expect(page.locator("#part-heading .grid-status")).to_contain_text("a second table")
    # columns headed by angles round the other way from the session's (counter-clockwise:
    # 0°, −90°, −180°, −270°): pasted in column order all the same, and said, as the file
    # preview says it (app.core.table_headers.turned_other_way)
    angled = "0°\t90°\t180°\t270°\n" + "\n".join(["10.74\t-0.50\t-11.20\t0.10"] * 10)
    paste(page, "#part-heading .readings-grid tbody input", angled)
    expect(grid.nth(0).locator("input").nth(1)).to_have_value("-0.50")  # position 2: in order
    expect(page.locator("#part-heading .grid-status")).to_contain_text(
        "headed 0°, 90°, 180°, 270°, but this session's positions 1–4 are at 0°, -90°, -180°, "
        "-270°: round the other way"
    )
    session_way = angled.replace("0°\t90°\t180°\t270°", "0°\t270°\t180°\t90°")
    paste(page, "#part-heading .readings-grid tbody input", session_way)
    expect(page.locator("#part-heading .grid-status")).to_contain_text("Pasted 10 rows")
    expect(page.locator("#part-heading .grid-status")).not_to_contain_text("other way")
    # a long table keyed by the turntable's angle: each reading at its angle's position
    # (clockwise positive, as a file's is saved), and said where the angles run the other
    # way from the session's (90° is position 4 under counter-clockwise turns)
    by_angle = "角度\t读数\n" + "\n".join(
        f"{angle}\t{value}"
        for angle, value in [(0, "10.70"), (90, "2.80"), (180, "-9.00"), (270, "-0.90")]
        for _ in range(10)
    )
    paste(page, "#part-heading .readings-grid tbody input", by_angle)
    expect(grid.nth(0).locator("input").nth(3)).to_have_value("2.80")  # 90°: position 4
    expect(grid.nth(0).locator("input").nth(1)).to_have_value("-0.90")  # 270° = -90°: 2
    expect(page.locator("#part-heading .grid-status")).to_contain_text(
        "The pasted angles run 0°, 90°, 180°, 270°, round the other way"
    )
    # a header naming the readings' unit other than the grid's: said, as a file under
    # another unit is refused (°/s saved as °/h would be 3600 times too small)
    per_second = "P1 (°/s)\tP2 (°/s)\tP3 (°/s)\tP4 (°/s)\n" + "\n".join(["0.0030\t-0.0001"] * 10)
    paste(page, "#part-heading .readings-grid tbody input", per_second)
    status = page.locator("#part-heading .grid-status")
    expect(status).to_contain_text(
        "The pasted header gives the readings in °/s, but the grid's unit is °/h: choose °/s"
    )
    expect(status).to_have_class(re.compile("error-text"))
    page.locator("#part-heading .unit").first.select_option("deg/s")
    paste(page, "#part-heading .readings-grid tbody input", per_second)
    expect(status).not_to_contain_text("choose °/s")
    # a row of units in a unit GyroLab does not read: said, never read as the grid's unit
    milli = "P1\tP2\tP3\tP4\nmdeg/s\tmdeg/s\tmdeg/s\tmdeg/s\n" + "\n".join(["2.98\t0.80"] * 10)
    paste(page, "#part-heading .readings-grid tbody input", milli)
    expect(status).to_contain_text("in mdeg/s, which GyroLab does not read")
    expect(status).to_have_class(re.compile("error-text"))
    # the handout's table as a text editor holds it, columns between spaces: its label
    # column's empty cells are lost between spaces, and the rows keep their first reading
    from tests.test_readings_formats import handout_with_spaces

    paste(page, "#part-heading .readings-grid tbody input", handout_with_spaces(fixed_width=True))
    horizontal = handout("handout_horizontal.csv")
    expect(grid.nth(0).locator("input").nth(0)).to_have_value(f"{horizontal[1][0]:.2f}")
    expect(grid.nth(9).locator("input").nth(3)).to_have_value(f"{horizontal[4][9]:.2f}")
    expect(status).to_contain_text("a row of means or another summary skipped")
    # a spreadsheet's failed formula first in the paste: a row of readings with a bad cell,
    # never taken for a header and skipped
    failed = "#DIV/0!\t2.88\t-9.11\t-0.96\n" + "\n".join(["10.74\t2.88\t-9.11\t-0.96"] * 9)
    paste(page, "#part-heading .readings-grid tbody input", failed)
    expect(status).not_to_contain_text("header row skipped")
    bad = page.locator("#part-heading .readings-grid input.invalid")
    expect(bad).to_have_count(1)
    expect(bad).to_have_attribute(
        "title", "'#DIV/0!' is a spreadsheet's error (a formula that failed), not a reading"
    )
    # a cell quoted back keeps its text but not a bidirectional control (it would show
    # the rest of the message reversed)
    reversed_cell = "10.74\t2.88\t-9.11\t-0.96\n\u202e°/s\t2.88\t-9.11\t-0.96"
    paste(page, "#part-heading .readings-grid tbody input", reversed_cell)
    expect(bad).to_have_attribute("title", "'°/s' is not a number")


def test_a_paste_longer_than_the_grid_is_held_and_saved_as_pasted(live_server, new_page):
    """A logger's export of 5,000 rows pasted into the grid: not built as 20,000 cells (a
    60,000-row paste froze the page for 14 s), but held, said, and saved as pasted."""
    page = new_page()
    log_in(page, live_server.url, "student", STUDENT_PASSWORD)
    start_practice(page, live_server.url)
    rows = [f"{10.7 + 0.001 * (k % 7):.3f}\t{-0.5 - 0.001 * (k % 5):.3f}" for k in range(5000)]
    paste(page, "#part-heading .readings-grid tbody input", "\n".join(rows))
    status = page.locator("#part-heading .grid-status")
    expect(status).to_contain_text("Pasted 5000 rows: too many to show as cells")
    expect(status).to_contain_text("Position 1: n = 5000, Position 2: n = 5000")
    expect(page.locator("#part-heading .readings-grid tbody tr")).to_have_count(10)
    with page.expect_navigation():
        page.locator("#part-heading .save-manual").click()
    cards = page.locator("#part-heading .step")
    expect(cards.nth(0)).to_contain_text("5000")
    expect(cards.nth(1)).to_contain_text("5000")
    # a bad cell anywhere in such a paste keeps nothing, and says where
    rows[4321] = "10.7\tabc"
    paste(page, "#part-heading .readings-grid tbody input", "\n".join(rows))
    expect(status).to_contain_text("nothing kept: row 4322, position 2")
    # more readings than a position holds: the server's refusal names the position
    paste(page, "#part-heading .readings-grid tbody input", "\n".join(["10.7"] * 100_001))
    expect(status).to_contain_text("Pasted 100001 rows")
    page.locator("#part-heading .save-manual").click()
    expect(status).to_contain_text("Position 1: Too many readings: at most 100000 per position.")


@pytest.mark.parametrize("locale", ["zh-CN"])  # the other test speaks English
def test_a_table_with_one_row_per_position_goes_down_the_columns(live_server, new_page, locale):
    """A sheet laid out one row per position ("位置1 | 10.74 | 10.65 …"), or notes typed
    so ("位置1：10.74 10.65 …", "P2 = 2.88, 2.69"): each position's readings go down its
    own column, as a file of it is read (app.core.readings). The label column was skipped
    and the rows put across the grid -- position 1's column held the first reading of
    every position, said to be "all valid" -- and the rest dropped."""
    page = new_page(locale)
    log_in(page, live_server.url, "student", STUDENT_PASSWORD)
    start_practice(page, live_server.url)
    columns = list(zip(*table("handout_horizontal.csv"), strict=True))
    said = "one row per position" if locale == "en-US" else "每行是一个位置"
    grid = "#part-heading .readings-grid tbody"
    rows = page.locator(f"{grid} tr")
    sheet = "\n".join(f"位置{k + 1}\t" + "\t".join(column) for k, column in enumerate(columns))
    paste(page, f"{grid} input", sheet)
    expect(page.locator("#part-heading .grid-status")).to_contain_text(said)
    for r in (0, 9):
        for k in range(4):
            expect(rows.nth(r).locator("input").nth(k)).to_have_value(columns[k][r])
    # typed notes, a position at a time: only its column changes
    paste(page, f"{grid} input", f"位置3：{' '.join(columns[0])}\n位置4：{' '.join(columns[1])}")
    paste(page, f"{grid} input", f"P2 = {', '.join(columns[3])}\nP1 = {', '.join(columns[0])}")
    expect(rows.nth(9).locator("input").nth(2)).to_have_value(columns[0][9])
    expect(rows.nth(0).locator("input").nth(1)).to_have_value(columns[3][0])
    expect(rows.nth(9).locator("input").nth(3)).to_have_value(columns[1][9])
    expect(rows.nth(0).locator("input").nth(0)).to_have_value(columns[0][0])
    expect(page.locator("#part-heading .readings-grid input.invalid")).to_have_count(0)
    # a sheet with a header that numbers the readings and each row's mean at its end
    means = [sum(map(float, column)) / len(column) for column in columns]
    sheet = (
        "位置\t"
        + "\t".join(str(k) for k in range(1, 11))
        + "\t平均值\n"
        + "\n".join(
            f"位置{k + 1}\t" + "\t".join(column) + f"\t{means[k]:.3f}"
            for k, column in enumerate(columns)
        )
    )
    paste(page, f"{grid} input", sheet)
    summary = "a column of means" if locale == "en-US" else "已跳过平均值等汇总列"
    expect(page.locator("#part-heading .grid-status")).to_contain_text(summary)
    expect(rows).to_have_count(10)
    for k in range(4):
        expect(rows.nth(9).locator("input").nth(k)).to_have_value(columns[k][9])


@pytest.mark.parametrize("locale", ["en-US"])  # the other test speaks Chinese
def test_a_loggers_record_pasted_keeps_its_times_out_of_the_positions(
    live_server, new_page, locale
):
    """Two columns copied from a logger's sheet, "Time (s) | Rate (°/h)", pasted into
    position 3's column: the times went into position 3 and the rates into position 4, "all
    valid". The time column is skipped; an IMU's record of several axes is not pasted but
    sent to the file method, which asks for the axis."""
    page = new_page(locale)
    log_in(page, live_server.url, "student", STUDENT_PASSWORD)
    start_practice(page, live_server.url)
    words = {
        "en-US": ("the time column skipped", "Nothing pasted"),
        "zh-CN": ("已跳过时间列", "未粘贴"),
    }[locale]
    rates = [row[2] for row in table("handout_horizontal.csv")]
    grid = "#part-heading .readings-grid tbody"
    third = f"{grid} tr:first-child input[data-column='3']"
    record = "Elapsed Time (s)\tRate (°/h)\n" + "\n".join(
        f"{0.1 * k:.1f}\t{rate}" for k, rate in enumerate(rates)
    )
    paste(page, third, record)
    status = page.locator("#part-heading .grid-status")
    expect(status).to_contain_text(words[0])
    rows = page.locator(f"{grid} tr")
    for r in (0, 9):
        expect(rows.nth(r).locator("input").nth(2)).to_have_value(rates[r])
        expect(rows.nth(r).locator("input").nth(3)).to_have_value("")
    axes = "time\tgx\tgy\tgz\n" + "\n".join(
        f"{0.1 * k:.1f}\t0.1\t0.2\t{r}" for k, r in enumerate(rates)
    )
    paste(page, f"{grid} input", axes)
    expect(status).to_contain_text(words[1])
    expect(status).to_have_class(re.compile("error-text"))
    expect(rows.nth(0).locator("input").nth(0)).to_have_value("")
