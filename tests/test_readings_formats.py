"""Readings files as spreadsheets in other locales write them: semicolons or tabs with
decimal commas, Chinese or spaced headers, a row-number column."""

from __future__ import annotations

import io

import numpy as np
import pytest

from app.core import position_records
from app.core.exceptions import UserError
from app.core.position_records import parse_position_csv
from app.core.readings import parse_readings_csv
from app.web.i18n import translate
from tests.factories import DATA, handout


def expected() -> list[np.ndarray]:
    return [np.array([10.74, 10.65]), np.array([-0.5, -0.4])]


@pytest.mark.parametrize(
    "text",
    [
        "position_1,position_2\n10.74,-0.50\n10.65,-0.40\n",
        "sample,position_1,position_2\n1,10.74,-0.50\n2,10.65,-0.40\n",
        "序号;位置1;位置2\n1;10,74;-0,50\n2;10,65;-0,40\n",
        "\ufeff序号,位置 1,位置 2\r\n1,10.74,-0.50\r\n2,10.65,-0.40\r\n",
        "Position 1\tPosition 2\n10,74\t-0,50\n10,65\t-0,40\n",
        "# exported by a spreadsheet\nposition_1;position_2\n10,74;-0,5\n10,65;-0,4\n",
    ],
    ids=["plain", "row-numbers", "semicolons-chinese", "chinese-bom-crlf", "tabs", "comment"],
)
def test_the_same_table_in_every_spelling(text):
    readings = parse_readings_csv(text)
    assert readings.layout == "wide"
    for got, want in zip(readings.positions, expected(), strict=True):
        np.testing.assert_allclose(got, want)


def test_long_layout_with_semicolons_and_decimal_commas():
    text = "position;angle_deg;value\n1;0;10,74\n1;0;10,65\n2;-90;-0,5\n"
    readings = parse_readings_csv(text)
    assert readings.angles_deg == [0.0, -90.0]
    np.testing.assert_allclose(readings.positions[0], [10.74, 10.65])


def test_a_decimal_comma_in_a_comma_separated_file_is_still_two_cells():
    with pytest.raises(UserError) as caught:
        parse_readings_csv("position_1\n10,74\nabc\n")
    assert caught.value.key == "csv.not_a_number" and caught.value.params["line"] == 3


@pytest.mark.parametrize(
    "text",
    [
        "10.74,-0.50,1.0\n10.65,-0.40,1.1\n",
        "1,10.74,-0.50,1.0\n2,10.65,-0.40,1.1\n",
        "0;10,74;-0,50;1,0\n1;10,65;-0,40;1,1\n",
    ],
    ids=["numbers-only", "row-numbers", "zero-based-semicolons"],
)
def test_a_table_without_a_header_is_read_without_its_row_numbers(text):
    readings = parse_readings_csv(text)
    assert len(readings.positions) == 3  # the counting column is not position 1
    np.testing.assert_allclose(readings.positions[0], [10.74, 10.65])
    np.testing.assert_allclose(readings.positions[2], [1.0, 1.1])


def test_two_headerless_columns_stay_a_time_value_record():
    with pytest.raises(UserError) as error:
        parse_readings_csv("0.0,10.74\n0.1,10.65\n")
    assert error.value.key == "csv.unknown_layout"
    from app.core.position_records import parse_static_record

    np.testing.assert_allclose(parse_static_record("0.0,10.74\n0.1,10.65\n"), [10.74, 10.65])


@pytest.mark.parametrize(
    "encoding", ["utf-8", "utf-8-sig", "gb18030", "utf-16", "utf-16-le", "utf-16-be"]
)
def test_chinese_headers_in_every_encoding_excel_writes(encoding):
    from app.core.text_files import decode_text

    data = "序号,位置1,位置2\n1,10.74,-0.50\n2,10.65,-0.40\n".encode(encoding)
    readings = parse_readings_csv(decode_text(data))
    for got, want in zip(readings.positions, expected(), strict=True):
        np.testing.assert_allclose(got, want)


def test_a_western_windows_programs_record_is_read_with_its_degree_sign():
    """A degree sign in Windows-1252 ("°/s": 0xB0 then "/") is neither UTF-8 nor GB18030: read as
    Windows-1252 whole or in blocks, its unit in the header known to every reader -- one
    position's record and a record read in blocks; a row of units under the names too."""
    from app.core.one_position_records import parse_one_position_record
    from app.core.static_record import read_static_record
    from app.core.text_files import decode_text, text_lines

    text = "Zeit [s];Drehrate [°/s]\r\n0,0;0,0041\r\n0,1;0,0042\r\n0,2;0,0040\r\n"
    data = text.encode("cp1252")
    assert decode_text(data) == text
    for chunk in (32, 1 << 20):  # the encoding told from the first block, as it holds "°"
        lines = list(text_lines(data, chunk=chunk))
        assert lines[0] == "Zeit [s];Drehrate [°/s]" and len(lines) == 4
        record = read_static_record(text_lines(data, chunk=chunk))
        assert record.unit == "deg/s"
        np.testing.assert_allclose(record.values, [0.0041, 0.0042, 0.0040])
    with pytest.raises(UserError) as error:
        parse_one_position_record(decode_text(data), "deg/h")
    assert error.value.key == "csv.unit_conflict"
    units_row = "time,rate\ns,deg/s\n0.0,0.0041\n0.1,0.0042\n"
    assert read_static_record(text_lines(units_row.encode())).unit == "deg/s"
    one = parse_one_position_record(units_row, "deg/s").readings.positions[0]
    np.testing.assert_allclose(one, [0.0041, 0.0042])
    with pytest.raises(UserError) as error:
        parse_one_position_record(units_row, "deg/h")
    assert error.value.key == "csv.unit_conflict"


def test_one_positions_record_typed_in_full_width_is_read_as_the_table_reads_it():
    """A Chinese input method in full-width mode, and the minus sign "−": one position's
    record reads them as the pasted table does (not as a header with no readings)."""
    from app.core.one_position_records import parse_one_position_record
    from app.core.position_records import parse_position_csv

    typed = "１０．７４\n１０．６５\n－０．５\n−0.4\n"
    want = [10.74, 10.65, -0.5, -0.4]
    one = parse_one_position_record(typed, "deg/h").readings.positions[0]
    np.testing.assert_allclose(one, want)
    np.testing.assert_allclose(parse_position_csv(typed)[0], want)


def test_a_long_text_is_made_plain_block_by_block_as_it_is_whole():
    """A long record's blocks of lines that are ASCII are left as they are; the others are
    normalised as the whole text would be -- full-width forms at a block's start and end,
    "。" between digits, a text without line ends."""
    import unicodedata

    from app.core.text_files import PLAIN_BLOCK, plain_text

    def whole(text: str) -> str:
        return unicodedata.normalize("NFKC", text).replace("\u2212", "-").replace("10。74", "10.74")

    header = "时间,角速率 (°/h)\n"
    lines = "".join(f"{k * 0.1:.1f},10.7{k % 10}\n" for k in range(PLAIN_BLOCK // 8))
    for text in (
        header + lines + "１０．７４，－０．５\n" + lines + "10。74\n−0.4",
        "１" * (PLAIN_BLOCK + 5),
        lines + "\n".join(["１０．７４"] * (PLAIN_BLOCK // 4)),
    ):
        assert len(text) > PLAIN_BLOCK
        assert plain_text(text) == whole(text)
    assert plain_text(header + lines).endswith(lines)


def test_binary_is_not_text():
    from app.core.text_files import decode_text

    with pytest.raises(UserError) as error:
        decode_text(bytes(range(256)) * 4)
    assert error.value.key == "csv.encoding"


@pytest.mark.parametrize(
    "marks",
    ["\x1a", "\x1a" * 100, "\x00" * 3000, "\x1a\x00\x00"],
    ids=["dos", "cp/m-padding", "power-lost", "both"],
)
def test_a_dos_programs_end_of_file_mark_is_not_part_of_the_file(marks):
    """An old logger's or terminal's file ends in Ctrl-Z (0x1A), several where the last
    record was padded; a logger that lost power leaves the space it had set aside for its
    file as NUL bytes: read as the same file without them, by every reader -- the table,
    one position's record, the API's CSV body, a record read in blocks (the marks, and a
    CRLF, across a block's end) -- and a Ctrl-Z inside a file is still not text."""
    from app.core.one_position_records import parse_one_position_record
    from app.core.position_records import parse_position_csv
    from app.core.static_record import read_static_record
    from app.core.text_files import decode_text, text_lines

    table = "位置1,位置2\r\n10.74,-0.50\r\n10.65,-0.40\r\n"
    for data in (table + marks, table.rstrip() + marks):
        readings = parse_readings_csv(data)
        for got, want in zip(readings.positions, expected(), strict=True):
            np.testing.assert_allclose(got, want)
        assert decode_text(data.encode("gb18030")) == data.rstrip("\x1a\x00")
        assert decode_text(data.encode("utf-16")) == data.rstrip("\x1a\x00")
    record = "time_s,value\r\n0.0,10.74\r\n0.1,10.65\r\n0.2,10.70\r\n" + marks
    one = parse_one_position_record(record, "deg/h").readings
    np.testing.assert_allclose(one.positions[0], [10.74, 10.65, 10.70])
    values, times = parse_position_csv(record.encode())
    np.testing.assert_allclose(values, [10.74, 10.65, 10.70])
    np.testing.assert_allclose(times, [0.0, 0.1, 0.2])
    for chunk in (7, 50, 1 << 20):  # marks and CRLFs cut at a block's end, or whole in one
        lines = list(text_lines(record.encode(), chunk=chunk))
        assert lines == ["time_s,value", "0.0,10.74", "0.1,10.65", "0.2,10.70"]
        static = read_static_record(text_lines(record.encode(), chunk=chunk))
        np.testing.assert_allclose(static.values, [10.74, 10.65, 10.70])
    for inside in ("0.0,10.74\x1a\r\n0.1,10.65\r\n", "0.0,10.74\r\n" + marks + "0.1,10.65\r\n"):
        with pytest.raises(UserError) as error:
            decode_text(inside.encode())
        assert error.value.key == "csv.encoding"
        for chunk in (5, 1 << 20):
            with pytest.raises(UserError) as error:
                list(text_lines(inside.encode(), chunk=chunk))
            assert error.value.key == "csv.encoding"


@pytest.mark.parametrize(
    "text",
    [
        "time_s,value\n0.0,10.74\n0.1,10.65\n",
        "time_s\tvalue\n0.0\t10.74\n0.1\t10.65\n",
        "time_s;value\r\n0,0;10,74\r\n0,1;10,65\r\n",
        "# a device's log\n0\t10,74\n0,1\t10,65\n",
    ],
    ids=["commas", "tabs", "semicolons-decimal-commas", "headerless-tabs-decimal-commas"],
)
def test_one_positions_record_in_every_spelling_the_lab_page_reads(text):
    """What a device or a script sends for one position (the API's ``text/csv``), and a
    static record: a tab or ``;`` between the columns, then decimal commas, as the lab
    page reads a table."""
    from app.core.position_records import parse_position_csv, parse_static_record

    values, times = parse_position_csv(text)
    np.testing.assert_allclose(values, [10.74, 10.65])
    np.testing.assert_allclose(times, [0.0, 0.1])
    np.testing.assert_allclose(parse_static_record(text), [10.74, 10.65])


def test_one_positions_record_with_commas_keeps_a_decimal_comma_two_cells():
    """In a comma-separated record "10,74" is a time and a value, as before."""
    from app.core.position_records import parse_position_csv

    values, times = parse_position_csv("10,74\n11,75\n")
    np.testing.assert_allclose(values, [74.0, 75.0])
    np.testing.assert_allclose(times, [10.0, 11.0])


@pytest.mark.parametrize(
    ("typed", "value"),
    [
        ("１０．７４", 10.74),
        ("－０．５", -0.5),
        ("１０，７４", 10.74),
        ("\u3000１２\u3000", 12.0),
        ("10。74", 10.74),  # the "." key in Chinese punctuation
    ],
)
def test_a_number_typed_with_a_chinese_input_methods_full_width_forms(typed, value):
    from app.core.typed_numbers import parse_typed_number

    assert parse_typed_number(typed) == value


def test_a_table_pasted_from_a_chinese_document_in_full_width_forms():
    """Full-width digits, points and commas (a table in a Chinese document) read as the
    same table; the Chinese headers stay Chinese."""
    text = "序号，位置１，位置２\n１，１０。７４，－０．５０\n２，１０．６５，－０。４０\n"
    readings = parse_readings_csv(text)
    for got, want in zip(readings.positions, expected(), strict=True):
        np.testing.assert_allclose(got, want)


@pytest.mark.parametrize(
    "header",
    [
        "位置1 (°/h),位置2 (°/h)",
        "Position 1 [deg/h],Position 2 [deg/h]",
        "位置1（°/h）,位置2（°/h）",
    ],
)
def test_a_unit_noted_in_brackets_after_a_column_name_is_not_part_of_it(header):
    readings = parse_readings_csv(f"{header}\n10.74,-0.50\n10.65,-0.40\n")
    for got, want in zip(readings.positions, expected(), strict=True):
        np.testing.assert_allclose(got, want)


@pytest.mark.parametrize(
    "text",
    [
        "陀螺寻北实验数据\n位置1,位置2\n10.74,-0.50\n10.65,-0.40\n",
        "实验数据\r\n2026-11-27 第3组\r\n位置1\t位置2\r\n10,74\t-0,50\r\n10,65\t-0,40\r\n",
    ],
    ids=["a title", "two title lines, tabs"],
)
def test_a_spreadsheets_title_above_the_table_is_passed_over(text):
    readings = parse_readings_csv(text)
    for got, want in zip(readings.positions, expected(), strict=True):
        np.testing.assert_allclose(got, want)


def test_past_a_title_the_lines_keep_their_numbers_and_more_titles_are_not_a_table():
    with pytest.raises(UserError) as caught:
        parse_readings_csv("标题\n位置1,位置2\n10.74,-0.50\n10.65,x\n")
    assert caught.value.key == "csv.not_a_number" and caught.value.params["line"] == 4
    # a title, the student's name and number in cells of their own, the date: passed over
    about = "陀螺寻北实验\n姓名：张三,学号：2023001\n日期：2026-12-07\n"
    readings = parse_readings_csv(about + "位置1,位置2\n10.74,-0.50\n")
    assert [v.tolist() for v in readings.positions] == [[10.74], [-0.5]]
    with pytest.raises(UserError) as caught:
        parse_readings_csv(about + "位置1,位置2\n10.74,-0.50\n10.65,x\n")
    assert caught.value.key == "csv.not_a_number" and caught.value.params["line"] == 6
    # more lines than a table has above it, or a row of numbers above: no table found
    for above in ("a\n" * 11, "1.5,2.5\nb\n"):
        with pytest.raises(UserError) as caught:
            parse_readings_csv(above + "位置1,位置2\n10.74,-0.50\n")
        assert caught.value.key == "csv.unknown_layout" and caught.value.params["line"] == 1
    # one column, no separator anywhere: a name above it is its header, nothing is skipped
    readings = parse_readings_csv("位置1\n10.74\n10.65\n")
    np.testing.assert_allclose(readings.positions[0], [10.74, 10.65])


@pytest.mark.parametrize(
    ("text", "values"),
    [
        ("11,5\n11,7\n10,9\n-0,5\n", [11.5, 11.7, 10.9, -0.5]),  # the first column falls
        ("value\n1,5\n2,5\n3,25\n", [1.5, 2.5, 3.25]),  # one name above two cells a line
        ("0,0123\n0,0131\n-0,0045\n0,0007\n", [0.0123, 0.0131, -0.0045, 0.0007]),
    ],
    ids=["falling", "one-name-header", "a-static-record"],
)
def test_one_column_with_decimal_commas_is_not_read_as_times_and_values(text, values):
    """A European logger's one column ("0,0123" per line) was read as time 0 and value 123:
    where the cells cannot be times and values, they are one number with a decimal comma."""
    from app.core.position_records import parse_position_csv, parse_static_record

    read, times = parse_position_csv(text)
    np.testing.assert_allclose(read, values)
    assert times is None
    np.testing.assert_allclose(parse_static_record(text), values)


@pytest.mark.parametrize(
    "text",
    ["0,10\n1,11\n2,9\n", "time_s,value\n0,10\n0,11\n", "0,10.5\n0,11.5\n", "1,-5\n0,5\n"],
    ids=["rising-times", "two-names", "a-point-in-the-value", "a-signed-value"],
)
def test_times_and_values_stay_times_and_values(text):
    from app.core.position_records import parse_position_csv

    _values, times = parse_position_csv(text)
    assert times is not None


def test_a_huge_whole_number_in_a_record_is_a_clear_refusal():
    from app.core.position_records import parse_position_csv

    with pytest.raises(UserError) as caught:
        parse_position_csv("9" * 5000 + ",5\n1,5\n")
    assert caught.value.key == "csv.out_of_range"


@pytest.mark.parametrize(
    ("text", "values"),
    [
        ("0,0123\n0,0131\n-0,0045\n0,0007\n", [0.0123, 0.0131, -0.0045, 0.0007]),
        ("# logger 7\nrate\n1,5\n2,5\n3,25\n", [1.5, 2.5, 3.25]),
    ],
    ids=["no-header", "one-name-header"],
)
def test_a_static_record_of_one_column_with_decimal_commas(text, values):
    """The bench-gyro record and ``gyrolab allan`` read a European logger's one column as
    numbers, not as times 0, 0, -0, 0 and values 123, 131, 45, 7."""
    from app.core.static_record import read_static_record

    record = read_static_record(io.StringIO(text))
    np.testing.assert_allclose(record.values, values)
    assert record.times_s is None


@pytest.mark.parametrize(
    "text",
    ["0,10\n1,11\n2,9\n", "time_s,value\n0,10\n0,11\n", "0,10.5\n0,11.5\n"],
    ids=["rising-times", "two-names", "a-point-in-the-value"],
)
def test_a_static_records_times_and_values_stay_so(text):
    from app.core.static_record import read_static_record

    assert read_static_record(io.StringIO(text)).times_s is not None


def test_a_decimal_comma_record_characterises_as_the_same_record_with_points():
    """The whole bench-gyro analysis, on an independent white-noise record written both
    ways: the same summary."""
    from app.courses.characterisation import characterise

    rates = np.random.default_rng(3).normal(0.01, 0.05, 100 * 610)
    points = "".join(f"{x:.4f}\n" for x in rates)
    commas = "rate_deg_h\n" + points.replace(".", ",")
    with_commas, with_points = (characterise(t.encode(), 100.0) for t in (commas, points))
    del with_commas["uploaded_at"], with_points["uploaded_at"]  # may fall in two minutes
    assert with_commas == with_points


@pytest.mark.parametrize(
    "units",
    ["°/h,°/h,°/h,°/h", "(°/h),(°/h),(°/h),(°/h)", "deg/h,deg/h,deg/h,deg/h", "度/小时,度/小时,,"],
)
def test_a_row_of_units_under_the_header_is_passed_over(units):
    """An instrument's export names the units under the names; like a unit after a name it
    is a note (the unit is the one chosen with the file), and the next lines keep their
    numbers."""
    text = f"position_1,position_2,position_3,position_4\n{units}\n10.74,-0.5,1.0,2\nx,1,1,1\n"
    with pytest.raises(UserError) as caught:
        parse_readings_csv(text)
    assert caught.value.params["line"] == 4  # the bad cell keeps its line
    good = parse_readings_csv(text.replace("x,1,1,1\n", "10.65,-0.4,1.1,2\n"))
    np.testing.assert_allclose(good.positions[0], [10.74, 10.65])


@pytest.mark.parametrize("units", ["s,°C", "s,value", "10.7,°/h"])
def test_a_row_that_is_not_only_units_is_still_read_and_refused(units):
    with pytest.raises(UserError) as caught:
        parse_readings_csv(f"position_1,position_2,position_3,position_4\n{units},1,1\n")
    assert caught.value.key == "csv.not_a_number" and caught.value.params["line"] == 2


def test_a_units_row_in_one_positions_record_and_a_static_record():
    from app.core.position_records import parse_position_csv
    from app.core.static_record import read_static_record

    values, times = parse_position_csv("time,rate\ns,deg/h\n0,10.7\n0.1,10.8\n")
    np.testing.assert_allclose(values, [10.7, 10.8])
    np.testing.assert_allclose(times, [0.0, 0.1])
    record = read_static_record(io.StringIO("time,rate,temp\ns,°/h,℃\n0,10.7,25\n0.1,10.8,25\n"))
    np.testing.assert_allclose(record.values, [10.7, 10.8])
    np.testing.assert_allclose(record.temperatures_c, [25.0, 25.0])


@pytest.mark.parametrize(
    ("header", "separator"),
    [
        ("position,rate", ","),
        ("Position,Reading (°/h)", ","),
        ("位置,角速度", ","),
        ("pos;rate_deg_h", ";"),
        ("序号\t位置\t读数 (°/h)\t时间 (s)", "\t"),
        ("Position No,Gyro Output", ","),
    ],
)
def test_one_reading_per_row_beside_its_position_in_a_students_spelling(header, separator):
    """The long table as spreadsheets name it: each position's readings, nothing merged
    into one record."""
    rows = [(1, 10.74), (1, 10.65), (2, -0.5), (2, -0.4), (3, -10.7), (4, 0.3), (4, 0.4)]
    width = header.count(separator) + 1
    lines = []
    for count, (position, value) in enumerate(rows, start=1):
        cells = {2: [position, value], 3: [position, value], 4: [count, position, value, count]}
        text = separator.join(str(c) for c in cells[width])
        lines.append(text.replace(".", ",") if separator == ";" else text)
    readings = parse_readings_csv(header + "\n" + "\n".join(lines) + "\n")
    assert readings.layout == "long" and readings.numbers == [1, 2, 3, 4]
    wanted = [[10.74, 10.65], [-0.5, -0.4], [-10.7], [0.3, 0.4]]
    for got, want in zip(readings.positions, wanted, strict=True):
        np.testing.assert_allclose(got, want)
    if "时间" in header:
        assert [t.tolist() for t in readings.times_s] == [[1, 2], [3, 4], [5], [6, 7]]


@pytest.mark.parametrize(
    ("labels", "numbers"),
    [
        (["3", "3"], [3]),
        (["P2", "P1", "P1"], [1, 2]),
        (["位置4", "第2位置", "位置4"], [2, 4]),
        (["0", "1", "2", "3"], [1, 2, 3, 4]),
        (["north", "east"], None),
    ],
    ids=["one-position", "names-sorted", "chinese", "from-zero", "labels"],
)
def test_a_long_files_positions_keep_the_numbers_it_gives(labels, numbers):
    text = "position,value\n" + "".join(f"{label},{k}.5\n" for k, label in enumerate(labels))
    readings = parse_readings_csv(text)
    assert readings.numbers == numbers and len(readings.positions) == len(set(labels))
    if labels[0] == "P2":  # sorted with their readings
        assert [p.tolist() for p in readings.positions] == [[1.5, 2.5], [0.5]]


def test_positions_given_by_the_turntables_angle():
    pairs = [(0, 1), (0, 2), (90, 3), (180, 4), (270, 5)]
    text = "angle,rate\n" + "".join(f"{a},{v}\n" for a, v in pairs)
    readings = parse_readings_csv(text)
    assert readings.angles_deg == [0.0, 90.0, 180.0, 270.0] and readings.numbers is None
    assert [p.tolist() for p in readings.positions] == [[1, 2], [3], [4], [5]]
    # a "position" column holding the dial's angles (0, 90, 180, 270) is read as the angles
    readings = parse_readings_csv(text.replace("angle", "Position (deg)"))
    assert readings.angles_deg == [0.0, 90.0, 180.0, 270.0] and readings.numbers is None
    # part B: the elevation in the meridian plane
    readings = parse_readings_csv("仰角,读数\n0,1.5\n90,2.5\n90,3.5\n")
    assert readings.angles_deg == [0.0, 90.0] and [p.size for p in readings.positions] == [1, 2]


@pytest.mark.parametrize(
    ("text", "key"),
    [
        ("angle,rate\n0,1\n90,2\n0,3\n", "csv.angle_returns"),
        ("position,rate\n1,1\nP1,2\n", "csv.position_twice_named"),
        ("position,rate\n1,1\n99999999999999999999,2\n", "csv.position_number"),
        ("position,rate\n1,1\n,2\n", "csv.no_position"),
        ("position,rate\n1,1\n2,abc\n", "csv.not_a_number"),
    ],
)
def test_a_long_file_that_cannot_be_read_says_why(text, key):
    with pytest.raises(UserError) as caught:
        parse_readings_csv(text)
    assert caught.value.key == key


def test_a_time_in_minutes_is_not_taken_for_seconds():
    readings = parse_readings_csv("position,time (min),rate\n1,0,1\n1,0.5,2\n2,1,3\n")
    assert readings.layout == "long" and readings.times_s is None


@pytest.mark.parametrize(
    ("header", "times"),
    [
        ("position,time_s,rate", ["0", "0.5", "60", "60.5"]),
        ("position,time (ms),rate", ["0", "500", "60000", "60500"]),
        ("position,time_ms,rate", ["0", "500", "60000", "60500"]),
        ("位置,时间（毫秒）,读数", ["0", "500", "60000", "60500"]),
        ("位置,时间,读数", ["12:00:00", "12:00:00.5", "12:01:00", "12:01:00.5"]),  # a clock
        (
            "position,time,rate",
            ["2026-11-28 12:00:00", "2026-11-28T12:00:00.5"] * 1
            + ["28.11.2026 12:01:00", "2026年11月28日 12时01分00.5秒"],
        ),
    ],
)
def test_a_long_tables_times_in_seconds_milliseconds_or_a_loggers_clock(header, times):
    """Before, a time in ms was passed over (the drift fit and warm-up check lost it) and
    a clock stamp ("12:00:01") refused as not a number."""
    rows = [
        f"{position},{time},{value}"
        for position, time, value in zip(
            [1, 1, 2, 2], times, [10.74, 10.65, 2.88, 2.69], strict=True
        )
    ]
    readings = parse_readings_csv("\n".join([header, *rows]) + "\n")
    first = readings.times_s[0][0]
    got = [list(t - first) for t in readings.times_s]
    assert got == [[0.0, 0.5], [60.0, 60.5]]
    with pytest.raises(UserError) as refused:
        parse_readings_csv(f"{header}\n1,25:00:00,10.74\n")
    assert refused.value.key == "csv.not_a_number"


def long_table(times_of) -> str:
    rows = ["position,angle_deg,time_s,value"]
    for position, angle in enumerate([0, -90, -180, -270], start=1):
        rows += [f"{position},{angle},{times_of(position, i)},{10.0 + 0.01 * i}" for i in range(12)]
    return "\n".join(rows) + "\n"


def test_a_long_tables_time_that_goes_back_is_refused_at_its_line():
    """The drift fit and the warm-up check read a position's times as one clock: a time
    that goes back within a position (two recordings joined, a clock set back) is refused
    where it is, in both languages -- before, the CLI solved it and the lab page took it."""
    text = long_table(lambda position, i: 100 * position + (i if i < 6 else i - 6))
    with pytest.raises(UserError) as refused:
        parse_readings_csv(text)
    assert refused.value.key == "csv.time_goes_back"
    assert refused.value.params == {"line": 8, "position": "1", "time": "100", "before": "105"}
    assert translate("csv.time_goes_back", "en", **refused.value.params).startswith(
        "Line 8: the time goes back within position 1 (100 after 105)"
    )
    assert translate("csv.time_goes_back", "zh-CN", **refused.value.params).startswith(
        "第 8 行：位置 1 内的时间倒退了（105 之后是 100）"
    )


def test_a_long_tables_coarse_clock_is_spread_and_one_stamp_a_position_passed_over():
    coarse = parse_readings_csv(long_table(lambda position, i: 100 * position + i // 4))
    assert coarse.times_s[0].tolist() == pytest.approx([100 + k / 4 for k in range(12)])
    assert [key for key, _ in coarse.left_out()] == ["csv.times_spread"]
    one = parse_readings_csv(long_table(lambda position, i: 100 * position))
    assert one.times_s is None and [key for key, _ in one.left_out()] == ["csv.times_dropped"]
    assert translate("csv.times_dropped", "en") == (
        "Every reading of a position has the same time: the time column was passed over, "
        "and the readings are taken without times."
    )


def _record_bodies(seed: int, count: int):
    """Records of one position in the spellings a device or a script sends, a few with a
    fault: headers, units rows, comments, blank lines, CRLF and bare CR ends, decimal
    commas under one name, falling times, cells numpy and the line-by-line reader might
    read differently ("nan", "1_0", "1e400", "1e", ".", "+-1", an empty cell, spaces)."""
    rng = np.random.default_rng(seed)
    heads = [
        "time_s,value",
        "value",
        "t,rate (deg/s)",
        "rate",
        '"time_s","value"',
        "# gyro",
        "",
        "0.5,10.7",
        "10.7",
        "time_s,value,temp",
    ]
    seconds = ["s,deg/h", "s,°/s", "# note", "", "0.6,10.8", "10.8", "deg/h"]
    odd = [
        "nan",
        "1_0",
        "1e400",
        "1e",
        ".",
        "+-1",
        "",
        "1,,2",
        "1,2,3",
        "11,5",
        "-.5",
        "5.",
        "1E+02",
        "0x1",
        "inf",
        " 3",
        "  ",
        "\t",
        "1.0 2.0",
        " 1.5 , 2.5\t",
        "1. 5",
        "- 1",
    ]
    for _ in range(count):
        width = int(rng.integers(1, 3))
        decimal_commas = rng.random() < 0.15
        separator = ", " if rng.random() < 0.2 else ","  # as a script may write them
        lines = [str(rng.choice(heads)), str(rng.choice(seconds))]
        start = float(rng.choice([1.0, 100.0, 0.0]))
        for k in range(int(rng.integers(0, 12))):
            value = f"{rng.normal(10, 2):.{int(rng.integers(0, 8))}f}"
            time = f"{start + k * rng.choice([0.1, -0.1, 1.0]):.3f}"
            if decimal_commas:  # "11,5": one column of numbers, or times and values?
                lines.append(value.replace(".", ","))
            else:
                lines.append(f"{time}{separator}{value}" if width == 2 else value)
        if lines[2:] and rng.random() < 0.4:
            lines[int(rng.integers(2, len(lines)))] = str(rng.choice(odd))
        end = str(rng.choice(["\n", "\r\n", "\r"], p=[0.6, 0.3, 0.1]))
        yield end.join(lines) + (end if rng.random() < 0.8 else "")


def _outcome(body: str):
    try:
        values, times = parse_position_csv(body.encode(), "deg/h")
    except UserError as error:
        return error.key, error.params
    return values.tolist(), None if times is None else times.tolist()


def test_a_plain_record_read_by_numpy_is_read_as_line_by_line(monkeypatch):
    # the fast reader (numpy's) of a comma-separated record of plain numbers must give
    # what the line-by-line reader gives, or leave the record to it
    bodies = list(_record_bodies(7, 3000))
    fast = [_outcome(body) for body in bodies]
    taken = sum(position_records._plain_numbers(body, "deg/h") is not None for body in bodies)
    monkeypatch.setattr(position_records, "_plain_numbers", lambda data, unit: None)
    for body, outcome in zip(bodies, fast, strict=True):
        assert outcome == _outcome(body), body
    assert taken > 400  # the fast reader took many of them, and left the rest
    assert taken < len(bodies) - 400


def test_many_plain_lines_are_read_by_numpy():
    times = np.arange(200_000) * 0.01
    values = np.random.default_rng(1).normal(10, 0.1, times.size)
    body = "time_s,value\n" + "\n".join(
        f"{t:.2f},{v:.6f}" for t, v in zip(times, values, strict=True)
    )
    assert position_records._plain_numbers(body, None) is not None
    read_values, read_times = parse_position_csv(body.encode(), None)
    assert np.array_equal(read_values, [float(f"{v:.6f}") for v in values])
    assert np.array_equal(read_times, [float(f"{t:.2f}") for t in times])


@pytest.mark.parametrize("separator", [",", ";", "\t"])
@pytest.mark.parametrize("hint", ["sep={}", '"sep={}"', "\ufeffsep={}", "SEP={}"])
def test_excels_first_line_naming_the_separator_is_read_as_excel_reads_it(separator, hint):
    # programs that write for Excel put "sep=;" above the table; every reader refused it
    from app.core.static_record import read_static_record
    from app.lab.uploads import csv_position

    first = hint.format(separator) + "\r\n"
    decimal = "," if separator != "," else "."
    table = first + "\r\n".join(
        separator.join(row)
        for row in [["P1", "P2", "P3"], ["10.74", "-0.5", "2.88"], ["10.65", "-0.4", "x"]]
    ).replace(".", decimal)
    with pytest.raises(UserError) as bad:
        parse_readings_csv(table)
    assert bad.value.params["line"] == 4  # the file's own line numbers
    readings = parse_readings_csv(table.replace("x", "2" + decimal + "69"))
    assert [v.tolist() for v in readings.positions] == [[10.74, 10.65], [-0.5, -0.4], [2.88, 2.69]]
    record = first + "\n".join(
        separator.join(row) for row in [["time_s", "rate"], ["0", "1.5"], ["0.1", "1.6"]]
    ).replace(".", decimal)
    assert read_static_record(io.StringIO(record)).values.tolist() == [1.5, 1.6]
    values, times, _ = csv_position(record.encode(), "deg/h")
    assert values.tolist() == [1.5, 1.6] and times.tolist() == [0.0, 0.1]


@pytest.mark.parametrize(
    "above", ["Lab 3, group 2\n", "实验三；第二组\n", "Lab 3\nZhang San, 2023001\n2026-12-07\n"]
)
def test_the_separator_is_the_tables_not_a_title_lines(above):
    # a title or a name above a table copied from a spreadsheet: the tab its rows hold
    table = "P1\tP2\tP3\n10,74\t-0,5\t2,88\n10,65\t-0,4\t2,69\n"
    readings = parse_readings_csv(above + table)
    assert [v.tolist() for v in readings.positions] == [[10.74, 10.65], [-0.5, -0.4], [2.88, 2.69]]


@pytest.mark.parametrize("label", ["单位", "单位：", "Unit", "units:"])
def test_a_row_of_units_named_as_such_in_its_first_cell_is_passed_over(label):
    text = f"序号,P1,P2\n{label},°/h,°/h\n1,10.74,-0.5\n2,10.65,-0.4\n"
    readings = parse_readings_csv(text)
    assert [v.tolist() for v in readings.positions] == [[10.74, 10.65], [-0.5, -0.4]]
    # beside a cell that is no unit, the label makes no row of units: said as such
    with pytest.raises(UserError) as caught:
        parse_readings_csv(f"序号,P1,P2\n{label},abc,°/h\n1,10.74,-0.5\n")
    assert caught.value.key == "csv.not_a_number" and caught.value.params["line"] == 2


@pytest.mark.parametrize(
    ("header", "angle"),
    [
        ("角度,读数", "{}°"),
        ("angle,rate", "{} deg"),
        ("dial,reading,note", "{}"),
        ("转台刻度,角速度", "{}度"),
        ("位置,刻度,读数", "{}°"),
    ],
)
def test_a_long_tables_angles_as_students_write_them(header, angle):
    # a turntable's angle with its unit in the cell, and the dial named as students name it
    rows = [(0, 11.51), (0, 11.49), (90, 3.2), (90, 3.1), (180, -11.4), (270, -3.1)]
    width = header.count(",") + 1
    lines = []
    for dial, value in rows:
        cells = [angle.format(dial), str(value)]
        if header.startswith("位置"):
            cells.insert(0, str([0, 90, 180, 270].index(dial) + 1))
        lines.append(",".join(cells + ["ok"] * (width - len(cells))))
    readings = parse_readings_csv(header + "\n" + "\n".join(lines) + "\n")
    assert readings.angles_deg == [0.0, 90.0, 180.0, 270.0]
    assert [v.tolist() for v in readings.positions] == [[11.51, 11.49], [3.2, 3.1], [-11.4], [-3.1]]


def test_a_quoted_decimal_comma_in_a_comma_separated_file_is_one_number():
    # LibreOffice in a European locale, saving with commas: each number quoted, "11,51"
    from app.core.static_record import read_static_record
    from app.lab.uploads import csv_position

    table = '"P1","P2","P3"\n"11,51","3,2","-11,4"\n"11,49","3,1","-11,5"\n'
    readings = parse_readings_csv(table)
    assert [v.tolist() for v in readings.positions] == [[11.51, 11.49], [3.2, 3.1], [-11.4, -11.5]]
    record = '"time_s","rate"\n"0,0","11,51"\n"0,1","11,49"\n"0,2","11,50"\n'
    assert read_static_record(io.StringIO(record)).values.tolist() == [11.51, 11.49, 11.5]
    values, times, _ = csv_position(record.encode(), "deg/h")
    assert values.tolist() == [11.51, 11.49, 11.5] and times.tolist() == [0.0, 0.1, 0.2]
    # unquoted, a comma still separates the cells: "11,51" is two cells
    assert parse_readings_csv("P1,P2\n11,51\n").positions[1].tolist() == [51.0]


def handout_with_spaces(fixed_width: bool) -> str:
    """The handout's Table 1 as a text file of columns between spaces: its "位置 1 2 3 4"
    header over a label column left empty, "采样值" beside the fifth row, the row of means
    last -- as a fixed-width export (padded) or typed with single spaces."""
    columns = handout("handout_horizontal.csv")
    cell = "{:>9}".format if fixed_width else str

    def line(label: str, values) -> str:
        return " ".join([cell(label), *(cell(f"{v:.2f}") for v in values)]).rstrip()

    lines = [line("位置", [1, 2, 3, 4]).replace(".00", "")]
    lines += [
        line("采样值" if row == 4 else "", [columns[k][row] for k in range(1, 5)])
        for row in range(10)
    ]
    return "\n".join([*lines, line("平均值", [10.71, 2.79, -8.95, -0.94])]) + "\n"


@pytest.mark.parametrize(
    "text",
    [
        handout_with_spaces(fixed_width=True),
        handout_with_spaces(fixed_width=False),
        "P1   P2   P3   P4\n"
        + "".join(
            " ".join(f"{columns:.2f}" for columns in row) + "\n"
            for row in zip(*handout("handout_horizontal.csv").values(), strict=True)
        ),
        "Position 1   Position 2   Position 3   Position 4\n"  # names holding a space
        + "".join(
            "  ".join(f"{v:.2f}" for v in row) + "\n"
            for row in zip(*handout("handout_horizontal.csv").values(), strict=True)
        ),
        "".join(  # MATLAB's save -ascii: no header, numbers in e-notation
            "".join(f"{v:16.7e}" for v in row) + "\n"
            for row in zip(*handout("handout_horizontal.csv").values(), strict=True)
        ),
    ],
    ids=["handout-fixed-width", "handout-single-spaces", "names", "names-with-spaces", "matlab"],
)
def test_a_table_of_columns_between_spaces_reads_as_its_csv(text):
    """A .txt or .dat of columns between spaces, as MATLAB, a fixed-width export or a
    student's editor writes it (the grid splits a paste so too): read as the same table
    in CSV.  Before, it was refused as an unknown layout."""
    readings = parse_readings_csv(text)
    as_csv = parse_readings_csv((DATA / "handout_horizontal.csv").read_text())
    for got, want in zip(readings.positions, as_csv.positions, strict=True):
        np.testing.assert_allclose(got, want)
    if "平均值" in text:
        assert readings.skipped == [(12, "平均值")]


def test_a_one_position_record_between_spaces_is_still_a_record():
    """Two columns between spaces are a logger's time and reading, not a table."""
    from app.core.one_position_records import parse_one_position_record

    text = "".join(f"{k * 0.1:.1f} {10.74 + 0.01 * (k % 3):.2f}\n" for k in range(20))
    with pytest.raises(UserError) as table:
        parse_readings_csv(text)
    assert table.value.key == "csv.unknown_layout"
    record = parse_one_position_record(text, "deg/h", None)
    assert record.readings.layout == "record" and record.readings.times_s[0][1] == 0.1


def test_the_lab_page_saves_a_text_file_of_columns_between_spaces(student_client):
    from tests.factories import new_session, post_json

    session_id = new_session(student_client)
    page = f"/lab/sessions/{session_id}"
    body = {"part": "heading", "unit": "deg/h", "text": handout_with_spaces(fixed_width=True)}
    preview = post_json(student_client, f"{page}/csv/preview", body, page)
    assert preview.status_code == 200, preview.text
    assert [p["n"] for p in preview.json()["positions"]] == [10, 10, 10, 10]
    assert preview.json()["notes"] == [
        "Line 12 ('平均值') was passed over: a summary of the readings, not a reading."
    ]
    assert post_json(student_client, f"{page}/csv", body, page).json()["saved"] == [1, 2, 3, 4]
    heading = student_client.get(f"{page}/results.json").json()["heading"]
    assert heading["theta_deg"] == pytest.approx(-10.753, abs=5e-4)  # the handout's θ


@pytest.mark.parametrize("error", ["#DIV/0!", "#N/A", "#VALUE!", "#ref!"])
def test_a_spreadsheets_error_value_is_a_problem_never_a_comment(error):
    """A row whose first cell is a failed formula ("#DIV/0!") was passed over as a "#"
    comment, with the row's other readings; now every reader names it, and a comment is
    still a comment."""
    from app.core.one_position_records import parse_one_position_record
    from app.core.static_record import read_static_record
    from app.core.text_files import text_lines

    rows = "10.74,2.88,-9.11,-0.96\n" * 3
    with pytest.raises(UserError) as table:
        parse_readings_csv(f"P1,P2,P3,P4\n{rows}{error},2.88,-9.11,-0.96\n")
    assert table.value.key == "csv.spreadsheet_error"
    assert table.value.params == {"line": 5, "column": "position_1", "value": error}
    assert translate("csv.spreadsheet_error", "en", **table.value.params).endswith(
        "is a spreadsheet's error (a formula that failed), not a reading: correct the "
        "formula or delete the cell."
    )
    hashed = "".join(f"#{line}" for line in rows.splitlines(keepends=True))  # commented out
    commented = parse_readings_csv(f"# exported 2026-11-28\nP1,P2,P3,P4\n{rows}{hashed}")
    assert [v.size for v in commented.positions] == [3, 3, 3, 3]
    record = "time_s,value\n" + "".join(f"{k / 10},{10 + k % 3}\n" for k in range(30))
    for read in (
        lambda text: parse_one_position_record(text, "deg/h", None),
        lambda text: read_static_record(text_lines(text.encode())),
    ):
        with pytest.raises(UserError) as refused:
            read(record + f"{error},10.74\n")
        assert refused.value.params["line"] == 32  # said at its line, not passed over


@pytest.mark.parametrize(
    "text",
    [
        "10.74, 2.88, -9.11, -0.96\n10.65, 2.69, -8.83, -0.96\n",  # typed in a text editor
        "10.74\t 2.88\t -9.11\t -0.96\n10.65\t 2.69\t -8.83\t -0.96\n",
        "10,74; 2,88; -9,11; -0,96\n10,65; 2,69; -8,83; -0,96\n",
        "10.74、2.88、-9.11、-0.96\n10.65、2.69、-8.83、-0.96\n",  # a Chinese input method's comma
        "位置1、位置2、位置3、位置4\n10.74、2.88、-9.11、-0.96\n10.65、2.69、-8.83、-0.96\n",
    ],
)
def test_a_table_typed_with_spaces_after_its_separators_or_chinese_commas(text):
    """A headerless table typed "10.74, 2.88, -9.11, -0.96" -- a space after each comma, as
    people type lists -- was "no known layout": its cells kept the spaces and no longer read
    as numbers.  So was one separated by 、, the comma a Chinese input method types."""
    readings = parse_readings_csv(text)
    assert [list(v) for v in readings.positions] == [
        [10.74, 10.65],
        [2.88, 2.69],
        [-9.11, -8.83],
        [-0.96, -0.96],
    ]


@pytest.mark.parametrize("encoding", ["utf-16-le", "utf-16-be"])
def test_utf16_without_its_mark_is_read_by_every_reader(encoding):
    """A Windows program's "Unicode" file written without a byte-order mark (.NET's
    UnicodeEncoding without a preamble, a LabVIEW string as UTF-16): was "not text" --
    now read whole and in blocks (a character cut across a block's end), as the API's
    body of one position and a roster's names."""
    from app.core.position_records import parse_position_csv
    from app.core.text_files import decode_text, text_lines, utf16_without_mark

    record = "时间 (s),角速率 (°/h)\r\n0.0,10.74\r\n0.1,10.65\r\n0.2,10.70\r\n"
    data = record.encode(encoding)
    assert utf16_without_mark(data) == encoding
    assert decode_text(data) == record
    for chunk in (51, 50, 1 << 20):  # told by the first block; a character cut at its end
        assert list(text_lines(data, chunk)) == record.splitlines()
    values, times = parse_position_csv(data)
    np.testing.assert_allclose(values, [10.74, 10.65, 10.70])
    np.testing.assert_allclose(times, [0.0, 0.1, 0.2])
    roster = "学号,姓名\r\n2023001,张三\r\n2023002,李四\r\n"
    assert decode_text(roster.encode(encoding)) == roster


def test_what_has_zero_bytes_but_is_no_utf16_is_not_read_as_it():
    """Raw float64 readings, NUL padding after a logger's last line, one-byte text and a
    file too short to tell are not taken for UTF-16; int16 counts whose high bytes are
    zero are, but decode to control characters and stay "not text"."""
    from app.core.exceptions import UserError
    from app.core.text_files import decode_text, utf16_without_mark

    floats = np.random.default_rng(3).normal(10.0, 0.5, 500).tobytes()
    padded = b"10.74\n10.65\n" + b"\x00" * 4000
    for data in (floats, padded, "10.74,°/h\n".encode("gb18030"), b"1\x00"):
        assert utf16_without_mark(data) is None
    assert decode_text(padded) == "10.74\n10.65\n"
    counts = np.arange(1, 250, dtype="<i2").tobytes()
    assert utf16_without_mark(counts) == "utf-16-le"
    for data in (floats, counts):
        with pytest.raises(UserError) as refused:
            decode_text(data)
        assert refused.value.key == "csv.encoding"


@pytest.mark.parametrize(
    "text",
    [
        "position_1,position_2,position_3,position_4",
        "序号,位置1,位置2,位置3,位置4\n",
        "位置,1,2,3,4\r\n,,,,\r\n",
        "sample,position_1,position_2\n\n\n",
    ],
)
def test_a_header_with_no_readings_under_it_is_said(text):
    """A template saved before it was filled in: "The file has no readings.", not a 500
    (the check for a row of means took the empty last row for one)."""
    from app.core.exceptions import UserError

    with pytest.raises(UserError) as refused:
        parse_readings_csv(text, part="heading")
    assert refused.value.key == "csv.empty"
