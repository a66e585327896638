"""A roster uploaded as the Excel workbook a student system hands out: student numbers held
as numbers come in whole, and a hostile or broken file is a clear refusal."""

from __future__ import annotations

import io
import re
import zipfile
from datetime import date
from urllib.parse import unquote

import pytest
import xlsxwriter
from sqlmodel import select

from app.accounts.roster_csv import parse_roster
from app.accounts.roster_workbook import (
    MAX_SHEET_ELEMENTS,
    MAX_UNPACKED_BYTES,
    OLE_MAGIC,
    cell_text,
)
from app.db import read_session
from app.models import User
from tests.factories import create_course, credentials_from, import_file

XLSX = "application/vnd.openxmlformats-officedocument.spreadsheetml.sheet"


def workbook(rows: list[list], first_sheet: str = "名单", more_sheets: int = 0) -> bytes:
    """An .xlsx as a spreadsheet writes one (XlsxWriter: numbers as numbers, text as text)."""
    buffer = io.BytesIO()
    book = xlsxwriter.Workbook(buffer, {"in_memory": True})
    sheet = book.add_worksheet(first_sheet)
    for r, row in enumerate(rows):
        for c, value in enumerate(row):
            if value is None:
                continue
            if isinstance(value, int | float):
                sheet.write_number(r, c, value)
            else:
                sheet.write_string(r, c, value)
    for k in range(more_sheets):
        book.add_worksheet(f"other{k}").write_string(0, 0, "not the roster")
    book.close()
    return buffer.getvalue()


def test_numbers_held_as_numbers_are_the_student_numbers():
    data = workbook(
        [
            ["学号", "姓名", "邮箱"],
            [2023010101, "张三", "zhang@example.edu"],
            [None, None, None],  # an empty row: passed over, the numbering kept
            ["007", "Bond", None],
            [202301010102.0, "李四", None],
        ],
        more_sheets=1,
    )
    parsed = parse_roster(data)
    assert parsed.problems == []
    assert [(r.line, r.username, r.display_name, r.email) for r in parsed.rows] == [
        (2, "2023010101", "张三", "zhang@example.edu"),
        (4, "007", "Bond", None),
        (5, "202301010102", "李四", None),
    ]


def test_a_problem_names_the_sheets_row():
    data = workbook([[2023010101, "张三", "not-mail"], [None], [2023010102, None, None]])
    parsed = parse_roster(data)  # no header: the columns in the usual order
    assert [(p.line, p.key) for p in parsed.problems] == [
        (1, "roster.bad_email"),
        (3, "roster.no_name"),
    ]


@pytest.mark.parametrize(
    ("value", "text"),
    [
        (None, ""),
        (2023010101.0, "2023010101"),
        (7, "7"),
        (12.5, "12.5"),
        (1e300, "1e+300"),
        (True, "TRUE"),
        (date(2026, 9, 1), "2026-09-01"),
        (" 张三 ", " 张三 "),
    ],
)
def test_cells_as_the_roster_reads_them(value, text):
    assert cell_text(value) == text


def broken_zip() -> bytes:
    return b"PK\x03\x04" + b"\x00" * 200


def zip_of(members: dict[str, bytes]) -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as archive:
        for name, content in members.items():
            archive.writestr(name, content)
    return buffer.getvalue()


def with_sheet(xml: bytes) -> bytes:
    """A real workbook whose first sheet's XML is replaced by ``xml``."""
    original = zipfile.ZipFile(io.BytesIO(workbook([["2024001", "张三"]])))
    members = {name: original.read(name) for name in original.namelist()}
    members["xl/worksheets/sheet1.xml"] = xml
    return zip_of(members)


LAUGHS = b"""<?xml version="1.0"?>
<!DOCTYPE lolz [<!ENTITY lol "lol"><!ENTITY lol2 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">
<!ENTITY lol3 "&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;">]>
<worksheet xmlns="http://schemas.openxmlformats.org/spreadsheetml/2006/main"><sheetData>
<row r="1"><c r="A1" t="inlineStr"><is><t>&lol3;</t></is></c></row></sheetData></worksheet>"""

EXTERNAL = b"""<?xml version="1.0"?>
<!DOCTYPE x [<!ENTITY secret SYSTEM "file:///etc/passwd">]>
<worksheet xmlns="http://schemas.openxmlformats.org/spreadsheetml/2006/main"><sheetData>
<row r="1"><c r="A1" t="inlineStr"><is><t>&secret;</t></is></c></row></sheetData></worksheet>"""


EMPTY_ROWS = (  # 1.6 million empty rows in 10 MB of XML: a 20 kB upload
    b'<?xml version="1.0"?><worksheet xmlns="http://schemas.openxmlformats.org/spreadsheetml/'
    b'2006/main"><sheetData>' + b"<row/>" * (MAX_SHEET_ELEMENTS * 8) + b"</sheetData></worksheet>"
)


def with_shared_strings(count: int, base: bytes | None = None) -> bytes:
    """A real workbook (``base``, else a roster's) whose shared strings are ``count``
    one-letter strings (1.5 million in a 67 kB upload took openpyxl 12 s to read)."""
    base = base or workbook([["学号", "姓名"], ["2024001", "张三"]])
    original = zipfile.ZipFile(io.BytesIO(base))
    members = {name: original.read(name) for name in original.namelist()}
    members["xl/sharedStrings.xml"] = (
        b'<?xml version="1.0"?><sst xmlns="http://schemas.openxmlformats.org/spreadsheetml/'
        b'2006/main">' + b"<si><t>a</t></si>" * count + b"</sst>"
    )
    return zip_of(members)


@pytest.mark.parametrize(
    ("data", "key"),
    [
        (OLE_MAGIC + b"\x00" * 500, "roster.old_excel"),
        (broken_zip(), "roster.bad_workbook"),
        (zip_of({"roster.csv": b"2024001,Zhang\n"}), "roster.bad_workbook"),  # a zipped CSV
        (with_sheet(LAUGHS), "roster.bad_workbook"),  # entity expansion: never expanded
        (with_sheet(EXTERNAL), "roster.bad_workbook"),  # an external entity: never read
        (with_sheet(b"<worksheet"), "roster.bad_workbook"),  # cut short
        (zip_of({"xl/big.bin": b"\x00" * (MAX_UNPACKED_BYTES + 1)}), "roster.workbook_too_large"),
        (with_sheet(EMPTY_ROWS), "roster.workbook_rows"),  # 20 kB: seconds of parsing
        (with_shared_strings(MAX_SHEET_ELEMENTS), "roster.workbook_rows"),  # the same
    ],
    ids=["xls", "broken-zip", "zipped-csv", "entity-expansion", "external-entity", "cut-short",
         "zip-bomb", "empty-rows", "shared-strings"],
)  # fmt: skip
def test_a_workbook_that_cannot_be_read_is_a_clear_refusal(data, key):
    parsed = parse_roster(data)
    assert parsed.rows == [] and [(p.line, p.key) for p in parsed.problems] == [(0, key)]


def test_the_course_page_imports_a_workbook(teacher_client):
    course_id = create_course(teacher_client)
    data = workbook([["学号", "姓名"], [2023010101, "张三"], ["007", "Bond"]])
    response = import_file(teacher_client, course_id, data, name="名单.xlsx")
    assert response.status_code == 200, response.text[:300]
    assert set(credentials_from(response.text)) == {"2023010101", "007"}
    with read_session() as db:
        usernames = set(db.exec(select(User.username).where(User.role == "student")).all())
    assert usernames == {"2023010101", "007"}


def test_the_course_page_names_an_old_excel_file_and_creates_nothing(teacher_client):
    course_id = create_course(teacher_client)
    teacher_client.cookies.set("gyrolab_lang", "zh-CN")
    response = import_file(teacher_client, course_id, OLE_MAGIC + b"\x00" * 500, name="a.xls")
    assert response.status_code == 400
    assert "无法读取这个旧版 Excel 工作簿（.xls" in response.text
    assert "名单未导入：" in response.text and "请修改以下各行" not in response.text  # no rows
    with read_session() as db:
        assert db.exec(select(User).where(User.role == "student")).first() is None


def old_workbook(rows: list[list], sheet: str = "名单") -> bytes:
    """An Excel 97-2003 workbook (.xls) as a school's records system exports a roster,
    written by xlwt (independent of the reader): numbers as numbers, dates as dates."""
    import xlwt

    book = xlwt.Workbook(encoding="utf-8")
    page = book.add_sheet(sheet)
    dated = xlwt.easyxf(num_format_str="YYYY-MM-DD")
    for r, row in enumerate(rows):
        for c, value in enumerate(row):
            if isinstance(value, date):
                page.write(r, c, value, dated)
            else:
                page.write(r, c, value)
    out = io.BytesIO()
    book.save(out)
    return out.getvalue()


def test_an_old_excel_roster_from_the_records_system_is_imported(teacher_client):
    """An .xls roster (学号 as numbers, a date column, Chinese names): every student
    created, the numbers whole -- before, "save it as .xlsx first"."""
    rows = [
        ["学号", "姓名", "入学日期"],
        [2023010101, "张三", date(2023, 9, 1)],
        [2023010102, "李四", date(2023, 9, 1)],
        ["007", "王五", ""],
    ]
    data = old_workbook(rows)
    assert data.startswith(OLE_MAGIC)
    parsed = parse_roster(data)
    assert [row.username for row in parsed.rows] == ["2023010101", "2023010102", "007"]
    assert [row.display_name for row in parsed.rows] == ["张三", "李四", "王五"]
    course_id = create_course(teacher_client)
    response = import_file(teacher_client, course_id, data, name="名单.xls")
    assert response.status_code == 200, response.text[:300]
    assert set(credentials_from(response.text)) == {"2023010101", "2023010102", "007"}


def test_uploaded_workbooks_are_parsed_through_defusedxml():
    """openpyxl uses defusedxml when it is installed: without it the entity tests above
    would expand (a small expansion passes as a roster row)."""
    from openpyxl.xml import DEFUSEDXML

    assert DEFUSEDXML


def test_a_student_systems_export_with_a_title_above_the_header():
    """A registrar's workbook: a merged title and a term line above "序号 学号 姓 名 性别"."""
    data = workbook(
        [
            ["2026 秋季学期 惯性导航实验 学生名单"],
            [None, None, "导出日期 2026-09-01"],
            ["序号", "学　号", "姓 名", "性别"],
            [1, 2023010101, "张三", "男"],
            [2, 2023010102, "李四", "女"],
        ]
    )
    parsed = parse_roster(data)
    assert parsed.problems == []
    assert [(r.line, r.username, r.display_name) for r in parsed.rows] == [
        (4, "2023010101", "张三"),
        (5, "2023010102", "李四"),
    ]


def test_title_lines_in_a_csv_and_a_header_without_names_names_its_line():
    csv_text = "惯性导航实验名单\n学生学号,学生姓名\n2024001,张三\n"
    assert [r.username for r in parse_roster(csv_text.encode()).rows] == ["2024001"]
    no_names = parse_roster("名单\n学号,邮箱\n2024001,a@b.cn\n".encode())
    assert [(p.line, p.key) for p in no_names.problems] == [(2, "roster.no_name_column")]


@pytest.mark.parametrize(
    ("encoding", "separator"), [("utf-16", "\t"), ("gb18030", "\t"), ("utf-8-sig", ";")]
)
def test_title_lines_above_a_tab_or_semicolon_separated_header(encoding, separator):
    """A student system's export saved as text: title lines ("课程名称：惯性导航") above a
    tab-separated header. The separator was sniffed from the title lines with the table,
    so each row was one cell and every student "a bad username"."""
    lines = [
        "课程名称：惯性导航实验",
        "学年学期：2026-2027-1",
        separator.join(["序号", "学号", "姓名", "行政班级"]),
        separator.join(["1", "2023010101", "张三", "光电2301"]),
        separator.join(["2", "2023010102", "欧阳 娜娜", "光电2301"]),
    ]
    parsed = parse_roster("\r\n".join(lines).encode(encoding))
    assert parsed.problems == []
    assert [(r.line, r.username, r.display_name) for r in parsed.rows] == [
        (4, "2023010101", "张三"),
        (5, "2023010102", "欧阳 娜娜"),
    ]


def test_english_headers_as_lms_exports_name_them():
    text = "Student No.;Name;Email address\n12345;Lee, Ann;ann@uni.edu\n"
    parsed = parse_roster(text.encode())
    assert parsed.problems == []
    assert [(r.username, r.display_name, r.email) for r in parsed.rows] == [
        ("12345", "Lee, Ann", "ann@uni.edu")
    ]


def test_a_roster_without_a_header_keeps_every_row():
    """A student named "login" on the second row is not a header: the first row has two
    cells, so the file has none."""
    parsed = parse_roster(b"2024001,Zhang\nlogin,Name\n2024003,Wang\n")
    assert [r.username for r in parsed.rows] == ["2024001", "login", "2024003"]
    assert parsed.problems == []


def test_the_passwords_download_speaks_the_page_language_and_imports_back(teacher_client):
    """The one-time passwords' columns are named as the page's table names them (用户名/学号,
    姓名, 初始密码); the same file imported into another course enrols the same students."""
    teacher_client.cookies.set("gyrolab_lang", "zh-CN")
    first = create_course(teacher_client, name="惯导 1 班")
    page = import_file(teacher_client, first, "学号,姓名\n2024001,张三\n".encode()).text
    href = re.search(r'id="download-credentials" href="data:text/csv;charset=utf-8,([^"]+)"', page)
    text = unquote(href.group(1).replace("&amp;", "&"))
    assert text.lstrip("\ufeff").splitlines()[0] == "用户名/学号,姓名,初始密码"
    second = create_course(teacher_client, name="惯导 2 班")
    again = import_file(teacher_client, second, text.encode("utf-8"))
    assert again.status_code == 200 and "2024001" in again.text
    with read_session() as db:
        assert db.exec(select(User).where(User.username == "2024001")).one().display_name == "张三"
