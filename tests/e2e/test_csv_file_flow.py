"""The lab page's CSV file, in a real browser: a spreadsheet's table chosen as a file is
previewed and saved; an Excel workbook (.xlsx) is read from its sheet of readings and
previewed as the same table saved as CSV, and so is an Excel 97-2003 one (.xls); an old
Office file that cannot be read is named as such, with the fix, in the page's language --
never garbled bytes sent to the server."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.io
from playwright.sync_api import expect

from tests.e2e.conftest import STUDENT_PASSWORD, axe_problems, log_in
from tests.e2e.test_lab_flow import start_practice, table
from tests.test_position_record_files import imu_file
from tests.test_workbook_readings import workbook

pytestmark = pytest.mark.e2e

OLD_EXCEL_WORDS = {
    "en": "This old Excel workbook (.xls, or another Office file) cannot be read",
    "zh-CN": "无法读取这个旧版 Excel 工作簿",
}
OLE_MAGIC = b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1"


def workbook_of(*sheets: list[list[str]], names: tuple[str, ...] = ()) -> bytes:
    """The rows in a workbook's sheets (named ``names``), numbers as numbers (as Excel
    holds them)."""
    as_held = [[rows[0], *([float(v) for v in row] for row in rows[1:])] for rows in sheets]
    return workbook(*as_held, names=names)


def csv_panel(page):
    """The heading part's CSV method, opened (after a save the page reloads: again)."""
    section = page.locator("#part-heading")
    section.locator(".method-tab[data-method=csv]").click()
    return section.locator('.method-panel[data-method="csv"]')


@pytest.mark.parametrize(("language", "width"), [("en", 1366), ("zh-CN", 390)])
def test_a_csv_file_is_previewed_and_saved_and_a_workbook_is_named(
    live_server, new_page, tmp_path, language, width
):
    page = new_page()
    log_in(page, live_server.url, "student", STUDENT_PASSWORD)
    page.context.add_cookies([{"name": "gyrolab_lang", "value": language, "url": live_server.url}])
    page.set_viewport_size({"width": width, "height": 844})
    start_practice(page, live_server.url)
    panel = csv_panel(page)
    # the file chooser and the unit fit a phone's width (the panel once pushed the page
    # sideways: a file input's own width in a grid column that could not shrink)
    assert page.evaluate("document.documentElement.scrollWidth") <= width
    rows = table("handout_horizontal.csv")
    header = [f"position_{k}" for k in range(1, 5)]

    old = tmp_path / "readings.xls"
    old.write_bytes(OLE_MAGIC + b"\x00" * 504)
    panel.locator(".csv-file").set_input_files(str(old))
    expect(panel.locator(".csv-preview .error-text")).to_contain_text(OLD_EXCEL_WORDS[language])
    expect(panel.locator(".accept-csv")).to_be_disabled()
    from tests.test_roster_workbook import old_workbook

    real = tmp_path / "表.xls"
    real.write_bytes(old_workbook([header, *([float(v) for v in row] for row in rows)], "数据"))
    panel.locator(".csv-file").set_input_files(str(real))  # a real .xls: read as its .xlsx
    expect(panel.locator(".csv-preview tbody tr")).to_have_count(4)
    expect(panel.locator(".accept-csv")).to_be_enabled()

    # a workbook of both parts, a sheet each: part A's read, the other offered
    book = tmp_path / "readings.xlsx"
    vertical = table("handout_vertical.csv")
    names = ("B 纬度", "A 寻北")
    book.write_bytes(workbook_of([header, *vertical], [header, *rows], names=names))
    panel.locator(".csv-file").set_input_files(str(book))
    preview = panel.locator(".csv-preview tbody tr")
    expect(preview).to_have_count(4)
    expect(preview.nth(0).locator("td").nth(2)).to_have_text(str(len(rows)))
    expect(panel.locator(".accept-csv")).to_be_enabled()
    from_book = preview.nth(0).locator("td").all_inner_texts()
    chosen = panel.locator("select.workbook-sheet")
    expect(chosen).to_have_value("A 寻北")
    assert axe_problems(page) == []  # the sheet's choice is labelled, as the page's fields
    chosen.select_option("B 纬度")
    expect(preview.nth(0).locator("td").nth(3)).to_have_text(
        f"{np.mean([float(r[0]) for r in vertical]):.3f}"
    )
    panel.locator("select.workbook-sheet").select_option("A 寻北")
    expect(preview.nth(0).locator("td")).to_have_text(from_book)

    readings = tmp_path / "readings.csv"  # the same sheet saved as CSV by a Chinese Excel
    readings.write_bytes("\n".join(",".join(row) for row in [header, *rows]).encode("gb18030"))
    panel.locator(".csv-file").set_input_files(str(readings))
    expect(preview).to_have_count(4)
    expect(preview.nth(0).locator("td")).to_have_text(from_book)  # the book read as its CSV
    with page.expect_navigation():
        panel.locator(".accept-csv").click()
    expect(page.locator("#take-history tbody tr")).to_have_count(4)


def test_one_positions_logger_files_are_saved_where_the_student_says(
    live_server, new_page, tmp_path
):
    """A real gyro's logger writes one file per position (its clock, the rate): the first
    is offered for the first empty position (this one in UTF-16 without its mark), the
    next for the position chosen in the preview -- its angle follows the choice -- and
    each is saved there.  The next comes
    from a Western Windows program (Windows-1252, "°/s" in its header): its unit is read
    from the header, and the preview asks for it while another is chosen; the last is a
    MATLAB file of ``t`` and ``omega`` (rad/s)."""
    page = new_page()
    log_in(page, live_server.url, "student", STUDENT_PASSWORD)
    page.context.add_cookies([{"name": "gyrolab_lang", "value": "zh-CN", "url": live_server.url}])
    page.set_viewport_size({"width": 390, "height": 844})
    start_practice(page, live_server.url)
    panel = csv_panel(page)
    columns = list(zip(*table("handout_horizontal.csv"), strict=True))

    def logger_file(position: int):
        path = tmp_path / f"pos{position}.csv"
        lines = ["时间,角速率 (°/h)"] + [
            f"2026-11-28 14:00:{k:02d}.0,{value}" for k, value in enumerate(columns[position - 1])
        ]
        # the first as a Windows program writes "Unicode": UTF-16 without its mark
        encoding = "utf-16-le" if position == 1 else "utf-8"
        path.write_bytes(("\n".join(lines) + "\n").encode(encoding))
        return str(path)

    panel.locator(".csv-file").set_input_files(logger_file(1))
    choice = panel.locator(".csv-preview select.record-position")
    expect(choice).to_have_value("1")
    expect(panel.locator(".csv-preview tbody tr td").first).to_have_text("1")
    with page.expect_navigation():
        panel.locator(".accept-csv").click()
    expect(page.locator("#take-history tbody tr")).to_have_count(1)

    panel = csv_panel(page)
    western = tmp_path / "pos3.csv"
    lines = ["Zeit;Drehrate [°/s]"] + [
        f"14:00:{k:02d},0;{float(value) / 3600:.9f}".replace(".", ",")
        for k, value in enumerate(columns[2])
    ]
    western.write_bytes(("\r\n".join(lines) + "\r\n").encode("cp1252"))
    panel.locator(".csv-file").set_input_files(str(western))
    expect(panel.locator(".csv-preview .error-text")).to_contain_text("读数单位为 °/s")
    accept = panel.locator(".accept-csv")
    expect(accept).to_be_disabled()
    assert float(accept.evaluate("b => getComputedStyle(b).opacity")) < 1  # and looks it
    panel.locator(".unit").select_option("deg/s")
    choice = panel.locator(".csv-preview select.record-position")
    expect(choice).to_have_value("2")  # the first position still empty
    angle_before = panel.locator(".csv-preview tbody tr td").nth(1).inner_text()
    choice.select_option("3")
    expect(panel.locator(".csv-preview tbody tr td").first).to_have_text("3")
    assert panel.locator(".csv-preview tbody tr td").nth(1).inner_text() != angle_before
    assert page.evaluate("document.documentElement.scrollWidth") <= 390
    with page.expect_navigation():
        panel.locator(".accept-csv").click()
    expect(page.locator("#take-history tbody tr")).to_have_count(2)

    # an IMU's record of three axes (EuRoC's layout, rad/s): the gyro's axis is chosen
    panel = csv_panel(page)
    panel.locator(".unit").select_option("rad/s")
    imu = tmp_path / "imu.csv"
    z_axis = [float(v) for v in columns[1]]
    imu.write_text(imu_file(z_axis), encoding="utf-8")
    panel.locator(".csv-file").set_input_files(str(imu))
    axis = panel.locator(".csv-preview select.record-column")
    expect(axis).to_have_value("w_RS_S_x [rad s^-1]")  # the first axis, said in a note
    expect(panel.locator(".csv-preview")).to_contain_text("3 列可能是陀螺的角速率")
    axis.select_option("w_RS_S_z [rad s^-1]")
    expect(panel.locator(".csv-preview tbody tr td").nth(3)).to_have_text(f"{np.mean(z_axis):.3f}")
    expect(panel.locator(".csv-preview select.record-position")).to_have_value("2")
    assert page.evaluate("document.documentElement.scrollWidth") <= 390
    with page.expect_navigation():
        panel.locator(".accept-csv").click()
    expect(page.locator("#take-history tbody tr")).to_have_count(3)

    # a MATLAB file of the last position (t and omega in rad/s, as MATLAB saves a log)
    panel = csv_panel(page)
    panel.locator(".unit").select_option("rad/s")
    rates = np.radians([float(v) for v in columns[3]]) / 3600.0
    mat = tmp_path / "pos4.mat"
    scipy.io.savemat(mat, {"t": 0.1 * np.arange(rates.size), "omega": rates})
    panel.locator(".csv-file").set_input_files(str(mat))
    expect(panel.locator(".csv-preview select.record-position")).to_have_value("4")
    mean = np.mean([float(v) for v in columns[3]])
    expect(panel.locator(".csv-preview tbody tr td").nth(3)).to_have_text(f"{mean:.3f}")
    with page.expect_navigation():
        panel.locator(".accept-csv").click()
    expect(page.locator("#take-history tbody tr")).to_have_count(4)
