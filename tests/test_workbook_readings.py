"""A student's readings saved as an Excel workbook (.xlsx): read from its sheet of readings
as a CSV file is, on the lab page and by ``gyrolab solve`` (workbooks written here by
xlsxwriter, not by the app's own reader's library)."""

from __future__ import annotations

import io
import json
from datetime import datetime, timedelta

import numpy as np
import pytest
import xlsxwriter

from app.core.exceptions import UserError
from app.core.readings import parse_readings_csv
from app.core.workbook_sheets import OLE_MAGIC
from app.core.workbook_text import READINGS_LIMITS, workbook_readings, workbook_text
from tests.factories import _form_token, handout, new_session, post_json
from tests.test_roster_workbook import with_shared_strings, zip_of
from tests.zip_faults import zip_patched


def workbook(
    *sheets: list[list[object]], formulas: bool = False, names: tuple[str, ...] = ()
) -> bytes:
    """A workbook of the given sheets' rows (named ``names``, else Sheet1…); ``formulas``:
    a last row of =AVERAGE under each numeric column, its value stored as Excel stores the
    last calculation."""
    buffer = io.BytesIO()
    book = xlsxwriter.Workbook(buffer, {"in_memory": True})
    for index, rows in enumerate(sheets):
        sheet = book.add_worksheet(names[index] if index < len(names) else None)
        for r, row in enumerate(rows):
            for c, value in enumerate(row):
                if value is not None:
                    sheet.write(r, c, value)
        if formulas and any(isinstance(v, float) for row in rows for v in row):
            width = max(len(row) for row in rows)
            numbers = [
                row
                for row in rows
                if len(row) == width and all(isinstance(v, float) for v in row[1:])
            ]
            for c in range(1, width):
                mean = float(np.mean([row[c] for row in numbers]))
                column = chr(ord("A") + c)
                first = len(rows) - len(numbers) + 1  # the readings' first row, from 1
                sheet.write_formula(
                    len(rows), c, f"=AVERAGE({column}{first}:{column}{len(rows)})", None, mean
                )
    book.close()
    return buffer.getvalue()


def handout_rows() -> list[list[object]]:
    columns = handout("handout_horizontal.csv")
    rows: list[list[object]] = [["序号", "位置1", "位置2", "位置3", "位置4"]]
    rows += [[n + 1, *(columns[k][n] for k in range(1, 5))] for n in range(10)]
    return rows


def test_the_sheet_of_readings_is_read_past_a_cover_sheet_and_its_average_row():
    cover = [["陀螺寻北实验 数据记录"], ["姓名", "张三"], ["日期", "2026-12-07"]]
    data = workbook(cover, handout_rows(), formulas=True)
    text = workbook_text(data)
    readings = parse_readings_csv(text)
    expected = handout("handout_horizontal.csv")
    for got, k in zip(readings.positions, range(1, 5), strict=True):
        assert got.tolist() == expected[k]  # each cell's value exactly, as typed
    # the =AVERAGE row, unlabelled, is told by its decimals and left out (sheet row 12)
    assert readings.means_row == 12


def test_a_line_the_readers_name_is_the_sheets_own_row():
    rows = handout_rows()
    rows[7][2] = "n/a"  # row 8 of the sheet, position 2
    data = workbook([[None], *rows])  # the table starts at row 2: row 1 left empty
    with pytest.raises(UserError) as bad:
        parse_readings_csv(workbook_text(data))
    assert bad.value.key == "csv.not_a_number" and bad.value.params["line"] == 9


def test_a_loggers_record_with_its_clock_reads_as_one_positions_record():
    from app.core.one_position_records import parse_one_position_record

    start = datetime(2026, 12, 7, 10, 0, 0)
    rows = [["时间", "角速度 (°/h)"]]
    rows += [[start + timedelta(seconds=0.1 * k), 10.0 + 0.01 * (k % 7)] for k in range(50)]
    buffer = io.BytesIO()
    book = xlsxwriter.Workbook(buffer, {"in_memory": True})
    sheet = book.add_worksheet()
    stamp = book.add_format({"num_format": "yyyy-mm-dd hh:mm:ss.000"})
    sheet.write_row(0, 0, rows[0])
    for r, (when, value) in enumerate(rows[1:], start=1):
        sheet.write_datetime(r, 0, when, stamp)
        sheet.write_number(r, 1, value)
    book.close()
    record = parse_one_position_record(workbook_text(buffer.getvalue()), "deg/h")
    times = record.readings.times_s[0]
    np.testing.assert_allclose(times, 0.1 * np.arange(50), atol=1e-3)
    assert record.readings.positions[0].tolist() == [row[1] for row in rows[1:]]


def shared_strings(count: int) -> bytes:
    return with_shared_strings(count, workbook([["P1", "P2"], [1.0, 2.0], [1.5, 2.5]]))


@pytest.mark.parametrize(
    ("data", "key"),
    [
        (OLE_MAGIC + b"\x00" * 500, "workbook.old_excel"),
        (b"PK\x03\x04 cut short", "workbook.unreadable"),
        (zip_of({"readings.csv": b"position_1\n10.74\n"}), "workbook.unreadable"),
        (
            zip_of({"xl/big.bin": b"\x00" * (READINGS_LIMITS.max_unpacked_bytes + 1)}),
            "workbook.too_large",
        ),
        (
            zip_of(
                {"xl/worksheets/sheet1.xml": b"<row/>" * (READINGS_LIMITS.max_sheet_elements + 1)}
            ),
            "workbook.too_many_cells",
        ),
        (shared_strings(READINGS_LIMITS.max_sheet_elements), "workbook.too_many_cells"),
        # what the zip module cannot open or read: were NotImplementedError or
        # RuntimeError (a 500 on the lab page, the roster, the characterisation)
        (zip_patched(workbook(handout_rows()), version=85), "workbook.unreadable"),
        (zip_patched(workbook(handout_rows()), method=9), "workbook.unreadable"),
        (zip_patched(workbook(handout_rows()), encrypted=True), "workbook.unreadable"),
    ],
    ids=[
        "xls",
        "cut",
        "zipped-csv",
        "bomb",
        "empty-rows",
        "shared-strings",
        "zip-version",
        "deflate64",
        "encrypted",
    ],
)
def test_a_workbook_that_cannot_be_read_is_refused_with_its_reason(data, key):
    with pytest.raises(UserError) as refused:
        workbook_text(data)
    assert refused.value.key == key


def test_the_lab_page_reads_a_workbook_as_the_text_it_previews_and_saves(student_client):
    session_id = new_session(student_client)
    page = f"/lab/sessions/{session_id}"
    data = workbook(handout_rows(), formulas=True)
    token = _form_token(student_client, page)
    headers = {"Content-Type": "application/octet-stream", "Accept": "application/json"}
    refused = student_client.post(f"{page}/csv/binary", content=data, headers=headers)
    assert refused.status_code == 403  # no CSRF token
    response = student_client.post(
        f"{page}/csv/binary", content=data, headers={**headers, "X-CSRF-Token": token}
    )
    assert response.status_code == 200, response.text
    text = response.json()["text"]
    body = {"part": "heading", "unit": "deg/h", "text": text}
    preview = post_json(student_client, f"{page}/csv/preview", body, page).json()
    assert [p["n"] for p in preview["positions"]] == [10, 10, 10, 10]
    assert "AVERAGE" in preview["notes"][0]
    saved = post_json(student_client, f"{page}/csv", body, page)
    assert saved.status_code == 200 and saved.json()["saved"] == [1, 2, 3, 4]
    theta = student_client.get(f"{page}/results.json").json()["heading"]["theta_deg"]
    assert theta == pytest.approx(-10.753, abs=5e-4)  # the handout's θ
    student_client.cookies.set("gyrolab_lang", "zh-CN")
    old = student_client.post(
        f"{page}/csv/binary",
        content=OLE_MAGIC + b"\x00" * 64,
        headers={**headers, "X-CSRF-Token": token},
    )
    assert old.status_code == 400 and "旧版 Excel 工作簿（.xls" in old.json()["detail"]
    assert "另存为" in old.json()["detail"]


def test_gyrolab_solve_reads_a_workbook(tmp_path, capsys):
    from app.cli.main import main

    path = tmp_path / "readings.xlsx"
    path.write_bytes(workbook(handout_rows(), formulas=True))
    assert main(["solve", "heading", str(path), "--json"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["theta_deg"] == pytest.approx(-10.753, abs=5e-4)
    assert "Line 12 was passed over" in err


def test_an_old_excel_workbook_of_readings_is_read_as_its_xlsx_is(tmp_path, capsys):
    """The handout's table saved as Excel 97-2003 (.xls, written by xlwt): the same
    readings as the .xlsx, on the lab page's reader and ``gyrolab solve``."""
    from app.cli.main import main
    from tests.test_roster_workbook import old_workbook

    rows = [[cell for cell in row if not str(cell).startswith("=")] for row in handout_rows()]
    data = old_workbook([[("" if cell is None else cell) for cell in row] for row in rows], "数据")
    readings = parse_readings_csv(workbook_text(data))
    expected = parse_readings_csv(workbook_text(workbook(handout_rows(), formulas=True)))
    assert [v.tolist() for v in readings.positions] == [v.tolist() for v in expected.positions]
    path = tmp_path / "readings.xls"
    path.write_bytes(data)
    assert main(["solve", "heading", str(path), "--json"]) == 0
    assert json.loads(capsys.readouterr()[0])["theta_deg"] == pytest.approx(-10.753, abs=5e-4)


def test_a_students_sheet_with_lines_about_the_table_above_it():
    # as students lay a sheet out: a title, their name and number in cells of their own,
    # the date, an empty row, then the table (the lines keep the sheet's row numbers)
    about = [["陀螺寻北实验数据"], ["姓名：张三", "学号：2023001"], ["日期", "2026-12-07"], [None]]
    rows = handout_rows()
    readings = parse_readings_csv(workbook_text(workbook([*about, *rows], formulas=True)))
    assert [v.size for v in readings.positions] == [10, 10, 10, 10]
    assert readings.means_row == 16  # the =AVERAGE row, sheet row 16


def test_workbooks_are_read_a_few_at_a_time(student_client):
    """Up to ≈ 7 s of parsing each: two at once in a process, one per student; past that
    a clear refusal at once, and the student's next try is read."""
    from app.web.work_slots import WORKBOOKS_AT_ONCE, pool

    session_id = new_session(student_client)
    page = f"/lab/sessions/{session_id}"
    headers = {
        "Content-Type": "application/octet-stream",
        "Accept": "application/json",
        "X-CSRF-Token": _form_token(student_client, page),
    }
    data = workbook(handout_rows())
    others = range(99_990, 99_990 + WORKBOOKS_AT_ONCE)
    for other in others:  # other students' workbooks under way
        pool("workbooks").take(other)
    try:
        busy = student_client.post(f"{page}/csv/binary", content=data, headers=headers)
        assert busy.status_code == 503 and "reading other workbooks" in busy.json()["detail"]
    finally:
        for other in others:
            pool("workbooks").give_back(other)
    read = student_client.post(f"{page}/csv/binary", content=data, headers=headers)
    assert read.status_code == 200 and read.json()["text"].startswith("序号\t位置1")


def test_gyrolab_allan_reads_a_workbook(tmp_path, capsys):
    from app.cli.main import main

    rates = np.random.default_rng(8).normal(10.0, 0.5, 7_200)
    path = tmp_path / "bench.xlsx"
    path.write_bytes(
        workbook([["time_s", "rate"], *([0.1 * k, float(r)] for k, r in enumerate(rates))])
    )
    assert main(["allan", str(path), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["samples"] == 7_200 and result["rate_hz"] == pytest.approx(10.0)


def latitude_rows() -> list[list[object]]:
    columns = handout("handout_vertical.csv")
    rows: list[list[object]] = [["序号", *(f"位置{k}" for k in columns)]]
    rows += [[n + 1, *(columns[k][n] for k in columns)] for n in range(len(columns[1]))]
    return rows


@pytest.mark.parametrize(
    ("names", "heading", "latitude"),
    [
        (("A 寻北", "B 纬度"), "A 寻北", "B 纬度"),
        (("Part B", "Part A"), "Part A", "Part B"),
        (("水平", "竖直"), "水平", "竖直"),
        (("A", "B"), "A", "B"),
        (("第一组", "第二组"), "第一组", "第一组"),  # names that say nothing: the first
    ],
)
def test_a_workbook_of_both_parts_offers_its_sheets_and_reads_each_parts_own(
    names, heading, latitude
):
    rows = {names[0]: handout_rows(), names[1]: latitude_rows()}
    if names[0] == "Part B":
        rows = {names[0]: latitude_rows(), names[1]: handout_rows()}
    data = workbook(*rows.values(), names=names)
    for part, expected in (("heading", heading), ("latitude", latitude)):
        book = workbook_readings(data, part=part)
        assert book.sheet == expected and book.sheets == names
        assert parse_readings_csv(book.text).positions[0].tolist() == [
            row[1] for row in rows[expected][1:]
        ]
    chosen = workbook_readings(data, sheet=names[1], part="heading")
    assert chosen.sheet == names[1]
    with pytest.raises(UserError) as missing:
        workbook_readings(data, sheet="Sheet9")
    assert missing.value.key == "workbook.no_such_sheet"


def test_the_lab_route_offers_the_sheets_and_reads_the_one_asked_for(student_client):
    session_id = new_session(student_client)
    page = f"/lab/sessions/{session_id}"
    headers = {
        "Content-Type": "application/octet-stream",
        "Accept": "application/json",
        "X-CSRF-Token": _form_token(student_client, page),
    }
    data = workbook(handout_rows(), latitude_rows(), names=("寻北", "纬度"))
    route = f"{page}/csv/binary"
    latitude = student_client.post(f"{route}?part=latitude", content=data, headers=headers).json()
    assert latitude["sheet"] == "纬度" and latitude["sheets"] == ["寻北", "纬度"]
    chosen = student_client.post(f"{route}?part=latitude&sheet=寻北", content=data, headers=headers)
    assert chosen.json()["sheet"] == "寻北" and chosen.json()["text"].startswith("序号\t位置1")
    missing = student_client.post(f"{route}?sheet=x", content=data, headers=headers)
    assert missing.status_code == 400 and "x" in missing.json()["detail"]
    bad_part = student_client.post(f"{route}?part=x", content=data, headers=headers)
    assert bad_part.status_code == 422


def test_a_damaged_old_excel_file_is_refused_without_a_word_on_stdout(capsys):
    """xlrd writes its warnings about a damaged file to stdout by default: they would land
    in ``gyrolab solve --json``'s output; they are kept from it."""
    from tests.test_roster_workbook import old_workbook

    data = old_workbook([[f"position_{k}" for k in range(1, 5)], *[[1.0, 2.0, 3.0, 4.0]] * 12])
    with pytest.raises(UserError) as refused:
        workbook_text(data[: len(data) - 700])  # cut short, as a failed copy leaves it
    assert refused.value.key == "workbook.old_excel"
    assert capsys.readouterr().out == ""
