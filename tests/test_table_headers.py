"""Tables as students make them from the handout: its own header "位置 | 1 | 2 | 3 | 4" with
a label column and a last row of means, columns named by the turntable's angle or "P1",
the table turned on its side -- each read as the positions it holds, the means passed over
and said."""

from __future__ import annotations

import json

import numpy as np
import pytest

from app.core.exceptions import UserError
from app.core.readings import parse_readings_csv
from app.core.table_headers import (
    column_name,
    header_angles,
    numbered_columns,
    summary_label,
    turned_other_way,
)
from app.web.i18n import translate
from tests.factories import DATA, handout, new_session, post_json

# the handout's Table 1 (four positions in the horizontal plane), as printed: the means row
# is the handout's own, rounded to two places
HANDOUT_MEANS = "平均值,10.71,2.79,-8.95,-0.94"


def handout_as_printed(name: str = "handout_horizontal.csv", separator: str = ",") -> str:
    """The handout's table laid out as the handout prints it: "位置 | 1 | 2 | 3 | 4", the
    label "采样值" beside the fifth row, and the row of means last."""
    columns = handout(name)
    lines = ["位置,1,2,3,4"]
    for row in range(len(columns[1])):
        label = "采样值" if row == 4 else ""
        lines.append(",".join([label, *(f"{columns[k][row]:.2f}" for k in range(1, 5))]))
    lines.append(HANDOUT_MEANS)
    return "\n".join(lines).replace(",", separator) + "\n"


@pytest.mark.parametrize("separator", [",", "\t", ";"])
def test_the_handout_table_as_printed_reads_as_its_readings_without_the_means(separator):
    readings = parse_readings_csv(handout_as_printed(separator=separator))
    expected = handout("handout_horizontal.csv")
    assert [values.size for values in readings.positions] == [10, 10, 10, 10]
    for got, k in zip(readings.positions, range(1, 5), strict=True):
        np.testing.assert_allclose(got, expected[k])
    # the row of means was the 12th line: passed over, and said
    assert readings.skipped == [(12, "平均值")]
    # what the handout printed as means is what the readings give, to its two places
    assert [round(float(v.mean()), 2) for v in readings.positions] == [10.71, 2.79, -8.95, -0.94]


@pytest.mark.parametrize(
    "header",
    [
        "0°,90°,180°,270°",
        "0 deg,90 deg,180 deg,270 deg",
        "0度,90度,180度,270度",
        "30°,120°,210°,300°",  # the dial's reading at the start need not be 0
        "0°,270°,180°,90°",  # turned the other way
        "0°,90°,180°,270°,备注",  # a notes column beside them
        "0,90,180,270",  # numbers alone: a header, not a first reading of 0, 90, 180, 270
        "1,2,3,4",
        "P1,P2,P3,P4",
        "pos. 1,pos. 2,pos. 3,pos. 4",
        "Position1,Position2,Position3,Position4",
        "第1位置,第2位置,第3位置,第4位置",
        "1号位置,2号位置,3号位置,4号位置",
        "位置一,位置二,位置三,位置四",
        "位置1（°/h）,位置2（°/h）,位置3（°/h）,位置4（°/h）",
        "位置1/(°/h),位置2/(°/h),位置3/(°/h),位置4/(°/h)",  # GB 3101: quantity/unit
    ],
)
def test_positions_named_as_students_name_them(header):
    readings = parse_readings_csv(f"{header}\n10.74,2.88,-9.11,-0.96\n10.65,2.69,-8.83,-0.96\n")
    assert [list(v) for v in readings.positions] == [
        [10.74, 10.65],
        [2.88, 2.69],
        [-9.11, -8.83],
        [-0.96, -0.96],
    ]


@pytest.mark.parametrize(
    ("header", "unit"),
    [
        ("角度/°,读数/(°/h)", "deg/h"),
        ("转台角度/度,陀螺输出/(°/s)", "deg/s"),
        ("angle/deg,rate/(deg/h)", "deg/h"),
    ],
)
def test_a_long_table_headed_quantity_over_unit(header, unit):
    """ "角度/°" and "读数/(°/h)", as Chinese lab tables head their columns (GB 3101), were
    no known layout; they read as the angle and the readings, the unit the header names."""
    rows = "0,10.7\n0,10.8\n90,2.9\n90,2.8\n180,-9.1\n180,-9.0\n270,-1.0\n270,-0.9\n"
    readings = parse_readings_csv(f"{header}\n{rows}")
    assert readings.angles_deg == [0.0, 90.0, 180.0, 270.0] and readings.named_unit == unit
    assert [list(v) for v in readings.positions] == [
        [10.7, 10.8],
        [2.9, 2.8],
        [-9.1, -9.0],
        [-1.0, -0.9],
    ]


def test_eight_positions_by_their_angles():
    header = ",".join(f"{45 * k}°" for k in range(8))
    readings = parse_readings_csv(header + "\n" + "1,2,3,4,5,6,7,8\n" * 3)
    assert [float(v[0]) for v in readings.positions] == [1, 2, 3, 4, 5, 6, 7, 8]


@pytest.mark.parametrize(
    ("cells", "more_rows", "expected"),
    [
        (["位置", "1", "2", "3", "4"], True, {1: 1, 2: 2, 3: 3, 4: 4}),
        (["位置", "1", "2"], True, {1: 1, 2: 2}),  # a label says it is a header
        (["1", "2"], True, None),  # two numbers alone could be a reading
        (["1", "2", "3", "4"], False, None),  # nothing under it: one row of readings
        (["0", "90", "180", "270"], False, None),
        (["10", "100", "190", "280"], True, None),  # bare numbers must start at 0
        (["0", "90", "180", "275"], True, None),
        (["1", "2", "4", "5"], True, None),
        (["0°", "90°", "180°"], True, {0: 1, 1: 2, 2: 3}),  # three positions: 120° apart only
        (["0°", "90°", "180°", "2"], True, None),
        (["a", "b", "c"], True, None),
    ],
)
def test_which_headers_number_the_positions(cells, more_rows, expected):
    if expected == {0: 1, 1: 2, 2: 3}:
        assert numbered_columns(cells, more_rows) is None  # 90° apart is not a third of a turn
        assert numbered_columns(["0°", "120°", "240°"], more_rows) == expected
    else:
        assert numbered_columns(cells, more_rows) == expected


def test_a_header_of_angles_is_no_longer_read_as_a_first_reading():
    """Before, "0,90,180,270" over a table of numbers was its first row of readings: 270 °/h
    in position 4 beside readings of about −1."""
    readings = parse_readings_csv("0,90,180,270\n10.74,2.88,-9.11,-0.96\n")
    assert [v.size for v in readings.positions] == [1, 1, 1, 1]
    assert float(readings.positions[3][0]) == -0.96


def test_one_row_of_numbers_counting_from_one_is_a_row_of_readings():
    """A first column 1, 2, 3 … counts rows only when there are rows to count."""
    readings = parse_readings_csv("1,2,3,4\n")
    assert [float(v[0]) for v in readings.positions] == [1.0, 2.0, 3.0, 4.0]


def test_the_table_turned_on_its_side():
    text = "位置1,10.74,10.65,10.84\n位置2,2.88,2.69\n位置3,-9.11,-8.83\n位置4,-0.96,-0.96\n"
    readings = parse_readings_csv(text)
    assert [v.size for v in readings.positions] == [3, 2, 2, 2]
    assert float(readings.positions[0][2]) == 10.84
    with pytest.raises(UserError) as twice:
        parse_readings_csv("p1,1,2\np1,3,4\np2,5\n")
    assert twice.value.key == "csv.position_twice" and twice.value.params["line"] == 2


@pytest.mark.parametrize(
    "label",
    ["位置{k}：", "位置{k} ： ", "P{k} = ", "Position {k}: ", "第{k}位置:", "position_{k}="],
)
@pytest.mark.parametrize("separator", [" ", ", ", "\t", "，"])
def test_notes_typed_one_line_per_position_its_name_ended_by_a_colon(label, separator):
    """Notes typed one line per position, "位置1：10.74 10.65 …": refused as an unknown
    layout, now read as the table turned on its side (the lab page's grid takes a paste of
    it so)."""
    columns = list(handout("handout_horizontal.csv").values())
    text = "\n".join(
        label.format(k=k + 1) + separator.join(f"{v:.2f}" for v in column)
        for k, column in enumerate(columns)
    )
    readings = parse_readings_csv(text)
    assert [v.tolist() for v in readings.positions] == columns


def turned_sheet(header: str | None, means: str | None) -> str:
    """The handout's part A laid out one row per position, as a spreadsheet: perhaps a
    header numbering the readings, perhaps each row's mean at its end."""
    columns = list(handout("handout_horizontal.csv").values())
    lines = [] if header is None else [header]
    for k, column in enumerate(columns):
        cells = [f"位置{k + 1}", *(f"{v:.2f}" for v in column)]
        if means is not None:
            cells.append(means.format(sum(column) / len(column)))
        lines.append(",".join(cells))
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize(
    ("header", "means", "said"),
    [
        ("位置," + ",".join(str(k) for k in range(1, 11)) + ",平均值", "{:.3f}", "summary_column"),
        (
            "Position," + ",".join(f"#{k}" for k in range(1, 11)) + ",Mean",
            "{:.2f}",
            "summary_column",
        ),
        (None, "{:.4f}", "means_column"),
        ("位置," + ",".join(f"第{k}次" for k in range(1, 11)), None, None),
    ],
    ids=[
        "numbered, 平均值",
        "Mean written at the readings' decimals",
        "unlabelled means",
        "header",
    ],
)
def test_a_table_turned_on_its_side_under_a_header_with_its_means(header, means, said):
    """One row per position under "位置 | 1 | 2 | … | 10 | 平均值": the header was read as the
    handout's "位置 | 1 | 2 | 3 | 4" -- ten positions, each the k-th reading of every
    position -- and an unlabelled mean at each row's end was one more reading."""
    readings = parse_readings_csv(turned_sheet(header, means))
    assert [v.tolist() for v in readings.positions] == list(
        handout("handout_horizontal.csv").values()
    )
    keys = [key for key, _ in readings.left_out()]
    assert keys == ([] if said is None else [f"csv.{said}_skipped"])


def test_a_turned_tables_genuine_last_reading_is_kept():
    """A last reading is no mean unless, in every row, it is the mean written longer."""
    text = turned_sheet(None, None).replace("\n", ",10.700\n", 1)  # longer, but no mean
    readings = parse_readings_csv(text)
    assert readings.positions[0].tolist()[-1] == 10.7 and readings.left_out() == []


def test_a_colon_that_follows_no_positions_name_is_no_label():
    with pytest.raises(UserError) as unknown:  # clock stamps: no position's name before ":"
        parse_readings_csv("10:00:00.1,10.7\n10:00:00.2,10.8\n10:00:00.3,10.6\n")
    assert unknown.value.key == "csv.unknown_layout"


def test_summary_rows_of_a_named_table_are_passed_over():
    text = (
        "sample,position_1,position_2\n1,10.74,-0.5\n2,10.65,-0.4\n"
        "mean,10.695,-0.45\nσ,0.06,0.07\nStd Dev:,0.06,0.07\n"
    )
    readings = parse_readings_csv(text)
    assert [v.size for v in readings.positions] == [2, 2]
    assert [label for _, label in readings.skipped] == ["mean", "σ", "Std Dev"]


def test_a_typeset_minus_sign_in_a_file_is_a_minus():
    readings = parse_readings_csv("p1,p2,p3\n\u22129.11,2.88,\u22120.96\n")
    assert [float(v[0]) for v in readings.positions] == [-9.11, 2.88, -0.96]


@pytest.mark.parametrize(
    ("cell", "name"),
    [
        ("位置 3", "position_3"),
        ("P 2", "position_2"),
        ("p_4", "position_4"),
        ("Pos #1", "position_1"),
        ("第 二 位置", "position_2"),
        ("第二个位置", "position_2"),
        ("time_s", "time_s"),
        ("Peak", "peak"),
    ],
)
def test_position_names(cell, name):
    assert column_name(cell) == name


def test_a_label_is_a_summary_only_when_it_says_so():
    assert summary_label(["", "平均值"]) == "平均值"
    assert summary_label(["Mean:"]) == "Mean"
    assert summary_label(["采样值"]) is None
    assert summary_label(["12", ""]) is None


def test_the_preview_says_which_row_it_passed_over_in_the_page_language(student_client):
    session_id = new_session(student_client)
    page = f"/lab/sessions/{session_id}"
    body = {"part": "heading", "unit": "deg/h", "text": handout_as_printed()}
    english = post_json(student_client, f"{page}/csv/preview", body, page)
    assert english.status_code == 200, english.text
    assert [p["n"] for p in english.json()["positions"]] == [10, 10, 10, 10]
    assert english.json()["notes"] == [
        "Line 12 ('平均值') was passed over: a summary of the readings, not a reading."
    ]
    student_client.cookies.set("gyrolab_lang", "zh-CN")
    chinese = post_json(student_client, f"{page}/csv/preview", body, page)
    assert chinese.json()["notes"] == ["第 12 行（“平均值”）已跳过：这是读数的汇总，不是读数。"]
    saved = post_json(student_client, f"{page}/csv", body, page)
    assert saved.status_code == 200 and saved.json()["saved"] == [1, 2, 3, 4]
    canonical = parse_readings_csv((DATA / "handout_horizontal.csv").read_text())
    results = student_client.get(f"{page}/results.json").json()["heading"]
    assert results["position_means_deg_h"] == pytest.approx(
        [float(v.mean()) for v in canonical.positions], abs=1e-12
    )
    assert results["theta_deg"] == pytest.approx(-10.753, abs=5e-4)  # the handout's θ


@pytest.mark.parametrize(
    "text",
    [
        "P1,P2,P3,P4\n11.51,3.2,-11.4,-3.1\n11.49,3.1,-11.5,-3.2\nMean,11.50,3.15,-11.45\n",
        "P1,P2,P3,P4\n11.51,3.2,-11.4,-3.1\n11.49,3.1,-11.5,-3.2\n平均值\n",
        "11.51,3.2,-11.4,-3.1\n11.49,3.1,-11.5,-3.2\nMean,11.50,3.15,-11.45,-3.15\n",
        "位置,读数\n1,11.51\n1,11.49\n2,3.2\n2,3.1\n3,-11.4\n3,-11.5\n4,-3.1\n4,-3.2\nmean,0\n",
        "位置1,11.51,11.49\n位置2,3.2,3.1\n位置3,-11.4,-11.5\n位置4,-3.1,-3.2\n平均值,1,2\n",
    ],
    ids=["label-under-position-1", "label-alone", "headerless", "long", "on-its-side"],
)
def test_a_summary_row_is_passed_over_in_every_layout_as_the_grid_passes_it(text):
    # the lab page's grid leaves such a pasted row out wherever its label stands; a file
    # was refused ("'Mean' is not a number"), or read "mean" as a fifth position
    readings = parse_readings_csv(text)
    assert [v.tolist() for v in readings.positions] == [
        [11.51, 11.49], [3.2, 3.1], [-11.4, -11.5], [-3.1, -3.2]
    ]  # fmt: skip
    assert [label.lower() for _, label in readings.skipped] in (["mean"], ["平均值"])


def handout_with_means(written) -> str:
    """The handout's Table 1 with a last row of each column's mean, unlabelled, as a
    spreadsheet's =AVERAGE row writes it (``written`` formats each mean)."""
    columns = handout("handout_horizontal.csv")
    lines = ["P1,P2,P3,P4"]
    lines += [",".join(f"{columns[k][row]:.2f}" for k in range(1, 5)) for row in range(10)]
    lines.append(",".join(written(float(np.mean(columns[k]))) for k in range(1, 5)))
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize(
    "written",
    [repr, "{:.3f}".format, "{:.10g}".format, "{:.4e}".format],
    ids=["repr", "3", "g", "e"],
)
def test_an_unlabelled_row_of_means_is_told_by_its_decimals_and_left_out(written):
    readings = parse_readings_csv(handout_with_means(written))
    assert [v.size for v in readings.positions] == [10, 10, 10, 10]
    assert readings.means_row == 12
    expected = handout("handout_horizontal.csv")
    for got, k in zip(readings.positions, range(1, 5), strict=True):
        np.testing.assert_allclose(got, expected[k])
    assert readings.left_out() == [("csv.means_row_skipped", {"line": 12})]


def test_a_row_that_is_not_every_columns_mean_stays_a_reading():
    # written to the readings' own two places, the means are readings as far as anyone
    # can tell; one column off by more than its last digit's half unit: a reading
    assert parse_readings_csv(handout_with_means("{:.2f}".format)).means_row is None
    shifted = handout_with_means("{:.3f}".format).rstrip("\n").rsplit(",", 1)
    text = f"{shifted[0]},{float(shifted[1]) + 0.002:.3f}\n"
    readings = parse_readings_csv(text)
    assert readings.means_row is None and [v.size for v in readings.positions] == [11] * 4
    # fewer than three readings above it: no pattern to tell it by
    assert parse_readings_csv("P1,P2\n1.1,2.1\n1.2,2.2\n1.15,2.15\n").means_row is None


def test_genuine_last_readings_are_never_taken_for_means():
    # 6,000 tables of a quantised gyro's readings (0.01 °/h, σ from a tenth of a step to
    # ten steps; one to four positions; 3 to 15 rows): the last row is always kept
    rng = np.random.default_rng(20261207)
    for _ in range(6_000):  # 100,000 over five seeds when written: none taken
        width, count = int(rng.integers(1, 5)), int(rng.integers(4, 16))
        sigma = 0.01 * 10.0 ** rng.uniform(-1, 1)
        table = np.round(rng.normal(rng.uniform(-15, 15, width), sigma, (count, width)), 2)
        text = "\n".join(",".join(f"{v:.{int(rng.integers(2, 4))}f}" for v in row) for row in table)
        readings = parse_readings_csv(",".join(f"P{k + 1}" for k in range(width)) + "\n" + text)
        assert readings.means_row is None, text


def test_the_preview_and_the_command_line_say_the_row_of_means_was_left_out(
    student_client, capsys, tmp_path
):
    from app.cli.main import main

    text = handout_with_means("{:.3f}".format)
    session_id = new_session(student_client)
    page = f"/lab/sessions/{session_id}"
    body = {"part": "heading", "unit": "deg/h", "text": text}
    english = post_json(student_client, f"{page}/csv/preview", body, page)
    assert [p["n"] for p in english.json()["positions"]] == [10, 10, 10, 10]
    assert english.json()["notes"] == [
        "Line 12 was passed over: it is each position's mean of the readings above it "
        "(a spreadsheet's AVERAGE row), not a reading."
    ]
    student_client.cookies.set("gyrolab_lang", "zh-CN")
    chinese = post_json(student_client, f"{page}/csv/preview", body, page)
    assert chinese.json()["notes"][0].startswith("第 12 行已跳过")
    path = tmp_path / "table.csv"
    path.write_text(text)
    assert main(["solve", "heading", str(path), "--json"]) == 0
    out, err = capsys.readouterr()
    assert "Line 12 was passed over" in err and "Line 12" not in out


@pytest.mark.parametrize(
    ("text", "numbers"),
    [
        ("位置3\n10.74\n10.65\n", [3]),
        ("P2,P4\n2.88,-0.96\n2.69,-0.96\n", [2, 4]),
        ("位置2,2.88,2.69\n位置4,-0.96,-0.96\n", [2, 4]),  # on its side
    ],
)
def test_a_table_of_some_positions_keeps_their_numbers(text, numbers):
    # as a long table does ("a file of position 3 alone is position 3"); refused before as
    # "position columns must be position_1 … position_N without gaps"
    readings = parse_readings_csv(text)
    assert readings.numbers == numbers and all(v.size == 2 for v in readings.positions)
    with pytest.raises(UserError) as twice:
        parse_readings_csv("P1,P2,P1\n1,2,3\n")
    assert twice.value.key == "csv.position_columns"


def test_a_file_of_one_positions_column_is_saved_as_that_position(student_client):
    session_id = new_session(student_client)
    page = f"/lab/sessions/{session_id}"
    body = {"part": "heading", "unit": "deg/h", "text": "位置3\n" + "\n".join(["-9.11"] * 10)}
    [row] = post_json(student_client, f"{page}/csv/preview", body, page).json()["positions"]
    assert row["position"] == 3 and row["n"] == 10
    assert post_json(student_client, f"{page}/csv", body, page).json()["saved"] == [3]


def stacked(first: str, second: str, separator: str = ",") -> str:
    """Both of the handout's tables in one file, one under the other, each under a title
    (as the handout prints them, its tables 1 and 2)."""
    lines = [first]
    for name in ("handout_horizontal.csv", "handout_vertical.csv"):
        columns = handout(name)
        if name.endswith("vertical.csv"):
            lines += ["", second]
        lines.append(separator.join(["位置", "1", "2", "3", "4"]))
        for row in range(len(columns[1])):
            lines.append(separator.join(["", *(f"{columns[k][row]:.2f}" for k in range(1, 5))]))
        lines.append(
            separator.join(["平均值", *(f"{np.mean(columns[k]):.2f}" for k in range(1, 5))])
        )
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize(
    ("first", "second"),
    [
        (
            "表 1 光纤陀螺在水平面内4个位置的采样值/(°/h)",
            "表 2 光纤陀螺在竖直面内4个位置的采样值/(°/h)",
        ),
        ("Part A: heading", "Part B: latitude"),
        ("A", "B"),
    ],
)
@pytest.mark.parametrize("separator", [",", "\t"])
def test_both_parts_tables_in_one_file_each_under_its_title(first, second, separator):
    text = stacked(first, second, separator)
    for part, name in (("heading", "handout_horizontal.csv"), ("latitude", "handout_vertical.csv")):
        readings = parse_readings_csv(text, part=part)
        expected = handout(name)
        assert [v.tolist() for v in readings.positions] == [expected[k] for k in range(1, 5)]
        assert len(readings.skipped) == 1  # its own row of means, on its own line
    assert parse_readings_csv(text, part="latitude").skipped[0][0] == 27


def test_a_second_table_whose_title_names_no_part_is_refused_not_read_as_readings():
    # "位置 | 1 | 2 | 3 | 4" again was read as a row of readings 1, 2, 3, 4, and the two
    # tables as one of 21 readings a position
    text = stacked("Table 1", "Table 2")
    for part in ("heading", None):
        with pytest.raises(UserError) as again:
            parse_readings_csv(text, part=part)
        assert again.value.key == "csv.header_again"
        assert again.value.params == {"line": 16, "header": 2}


def test_a_title_names_a_part_only_where_it_names_one_without_numbers():
    from app.core.part_names import part_named, part_titles

    assert part_named("表 2 光纤陀螺在竖直面内4个位置的采样值") == "latitude"
    assert part_named("Sheet B") is None and part_named("b") == "latitude"
    assert part_named("寻北实验：水平面与竖直面") is None  # both parts: neither
    text = "水平,1.5,2.5\n竖直面\nheading\n"
    assert [named for _, _, named in part_titles(text)] == ["latitude", "heading"]


def test_each_parts_csv_panel_takes_its_own_table_of_the_file(student_client):
    session_id = new_session(student_client)
    page = f"/lab/sessions/{session_id}"
    text = stacked(
        "表 1 光纤陀螺在水平面内4个位置的采样值", "表 2 光纤陀螺在竖直面内4个位置的采样值"
    )
    for part, name in (("heading", "handout_horizontal.csv"), ("latitude", "handout_vertical.csv")):
        body = {"part": part, "unit": "deg/h", "text": text}
        rows = post_json(student_client, f"{page}/csv/preview", body, page).json()["positions"]
        means = [round(float(np.mean(handout(name)[k])), 3) for k in range(1, 5)]
        assert [round(row["mean_deg_h"], 3) for row in rows] == means
        assert post_json(student_client, f"{page}/csv", body, page).json()["saved"] == [1, 2, 3, 4]


def test_a_headers_angles_and_which_way_they_run():
    assert header_angles(["0°", "90°", "180°", "270°"], True) == [0, 90, 180, 270]
    assert header_angles(["序号", "0", "90", "180", "270"], True) == [0, 90, 180, 270]
    assert header_angles(["位置", "1", "2", "3", "4"], True) is None  # counting, no angles
    assert header_angles(["P1", "P2", "P3", "P4"], True) is None
    ccw = [0.0, -90.0, -180.0, -270.0]  # lab-reference §3: clockwise positive
    assert turned_other_way([0, 90, 180, 270], ccw)
    assert turned_other_way([30, 120, 210, 300], ccw)  # from any start
    assert not turned_other_way([0, 270, 180, 90], ccw)  # the dial read the session's way
    assert not turned_other_way([0, 90, 180, 270], [0, 90, 180, 270])
    assert not turned_other_way([0, 180], [0, -180])  # two positions: either way alike
    assert not turned_other_way([0, 90, 180, 270], [0, 90, 180])
    assert turned_other_way([0, 120, 240], [0, -120, -240])
    assert not turned_other_way([0, 90, 180, 270], [0, 45, 90, 135])  # neither way


def test_a_header_of_angles_round_the_other_way_is_said_and_read_in_column_order(
    student_client, capsys, tmp_path
):
    """The handout turns counter-clockwise: positions 1-4 at 0°, −90°, −180°, −270°.  A
    header "0°, 90°, 180°, 270°" may be the turns made or the dial's readings; the columns
    stay positions 1-4 in order, and the preview and ``solve`` say the angles run the
    other way, so that a student whose dial it is can check."""
    from app.cli.main import main

    rows = "\n".join(
        ",".join(f"{v:.2f}" for v in row)
        for row in zip(*handout("handout_horizontal.csv").values(), strict=True)
    )
    session_id = new_session(student_client)  # counter-clockwise
    page = f"/lab/sessions/{session_id}"

    def preview(header: str, path: str = page) -> dict:
        body = {"part": "heading", "unit": "deg/h", "text": f"{header}\n{rows}\n"}
        response = post_json(student_client, f"{path}/csv/preview", body, path)
        assert response.status_code == 200, response.text
        return response.json()

    other_way = preview("0°,90°,180°,270°")
    assert [p["position"] for p in other_way["positions"]] == [1, 2, 3, 4]
    assert [p["angle_deg"] for p in other_way["positions"]] == [0, -90, -180, -270]
    assert other_way["notes"] == [
        "The columns are headed 0°, 90°, 180°, 270°, but this session's positions 1–4 are "
        "at 0°, -90°, -180°, -270°: round the other way. The columns are read in order as "
        "positions 1–4; if the headings are the dial's readings, check the session's "
        "turning direction before saving."
    ]
    assert preview("0°,270°,180°,90°")["notes"] == []  # the session's way round
    assert preview("位置,1,2,3,4".replace("位置,", ""))["notes"] == []  # no angles
    student_client.cookies.set("gyrolab_lang", "zh-CN")
    assert preview("0°,90°,180°,270°")["notes"][0].startswith("各列的表头为 0°, 90°, 180°, 270°")
    clockwise = new_session(student_client, rotation="cw")
    assert preview("0°,90°,180°,270°", f"/lab/sessions/{clockwise}")["notes"] == []

    path = tmp_path / "angles.csv"
    path.write_text(f"0°,90°,180°,270°\n{rows}\n")
    assert main(["solve", "heading", str(path), "--json"]) == 0
    out, err = capsys.readouterr()
    assert "give --rotation cw" in err and "--rotation" not in out
    assert main(["solve", "heading", str(path), "--json", "--rotation", "cw"]) == 0
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize(
    ("text", "unit"),
    [
        ("位置1 (°/s),位置2 (°/s),位置3 (°/s),位置4 (°/s)\n", "deg/s"),
        ("位置1（度/秒）,位置2（度/秒）,位置3（度/秒）,位置4（度/秒）\n", "deg/s"),
        ("P1 [rad/s],P2 [rad/s],P3 [rad/s],P4 [rad/s]\n", "rad/s"),
        ("序号,P1,P2,P3,P4\n单位：,°/h,°/h,°/h,°/h\n", "deg/h"),  # a row of units
        ("位置,1,2,3,4\n,(度/小时),(度/小时),(度/小时),(度/小时)\n", "deg/h"),
        ("time (s),P1 (°/s),P2 (°/h),P3,P4\n", None),  # two units: neither is said
        ("P1,P2,P3,P4\n", None),
        ("P1,P2,P3,P4,wind (m/s)\n", None),  # a speed is no rate of turn: neither read nor refused
    ],
)
def test_the_rate_unit_a_tables_header_names(text, unit):
    readings = parse_readings_csv(text + "0,10.74,2.88,-9.11,-0.96\n" * 2)
    assert readings.named_unit == unit


def test_a_table_in_degrees_a_second_is_never_read_as_degrees_an_hour(
    student_client, capsys, tmp_path
):
    """°/s read as °/h is 3600 times too small.  A table whose header names its unit is
    refused under another one on the lab page, as a logger's record is; ``gyrolab solve``
    reads it in the unit the header names unless told otherwise, and refuses a clash."""
    from app.cli.main import main

    columns = handout("handout_horizontal.csv")
    text = "位置1 (°/s),位置2 (°/s),位置3 (°/s),位置4 (°/s)\n" + "\n".join(
        ",".join(f"{columns[k][row] / 3600:.9f}" for k in range(1, 5)) for row in range(10)
    )
    session_id = new_session(student_client)
    page = f"/lab/sessions/{session_id}"
    body = {"part": "heading", "unit": "deg/h", "text": text}
    refused = post_json(student_client, f"{page}/csv/preview", body, page)
    assert refused.status_code == 400
    assert refused.json()["detail"] == (
        "The file's header gives the readings in °/s, but °/h is chosen: choose °/s."
    )
    assert post_json(student_client, f"{page}/csv", body, page).status_code == 400
    saved = post_json(student_client, f"{page}/csv", {**body, "unit": "deg/s"}, page)
    assert saved.status_code == 200 and saved.json()["saved"] == [1, 2, 3, 4]
    results = student_client.get(f"{page}/results.json").json()["heading"]
    assert results["theta_deg"] == pytest.approx(-10.753, abs=5e-4)  # the handout's θ

    path = tmp_path / "per-second.csv"
    path.write_text(text)
    assert main(["solve", "heading", str(path), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["theta_deg"] == pytest.approx(-10.753, abs=5e-4)
    assert main(["solve", "heading", str(path), "--unit", "deg/h"]) == 2
    assert "but °/h is chosen: choose °/s" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("reader", "text", "unit"),
    [
        ("table", "P1 (mdeg/s),P2 (mdeg/s),P3 (mdeg/s),P4 (mdeg/s)\n", "mdeg/s"),
        ("table", "P1,P2,P3,P4\nmdeg/s,mdeg/s,mdeg/s,mdeg/s\n", "mdeg/s"),
        ("table", "位置,1,2,3,4\n单位,度/分,度/分,度/分,度/分\n", "度/分"),
        ("table", "位置1 [°/min],位置2 [°/min],位置3 [°/min],位置4 [°/min]\n", "°/min"),
        ("record", "time_s,rate (mdeg/s)\n", "mdeg/s"),
        ("record", "time_s,value\ns,mrad/s\n", "mrad/s"),
        ("bench", "time_s,gyro (mdeg/s)\n", "mdeg/s"),
        ("bench", "time,gyro\ns,deg/min\n", "deg/min"),
    ],
)
def test_a_rate_in_a_unit_gyrolab_does_not_read_is_refused_by_name(reader, text, unit):
    """A milli-degree a second read as °/s would be 1000 times too large, as °/h 3.6 times
    too small: refused, naming the unit, by the table, one-position record and bench
    record readers alike (before, a header's unit was passed over as a note and a row of
    units refused as "'mdeg/s' is not a number")."""
    from app.core.one_position_records import parse_one_position_record
    from app.core.static_record import read_static_record
    from app.core.text_files import text_lines

    rows = (
        "0,10.74,2.88,-9.11,-0.96\n"
        if reader == "table"
        else "".join(f"{k * 0.1:.1f},{10.74 + 0.01 * (k % 3)}\n" for k in range(20))
    )
    with pytest.raises(UserError) as refused:
        if reader == "table":
            labelled = text.startswith("位置,")  # the handout's label column: a cell first
            parse_readings_csv(text + (rows if labelled else rows.split(",", 1)[1]) * 2)
        elif reader == "record":
            parse_one_position_record(text + rows, "deg/h", None)
        else:
            read_static_record(text_lines((text + rows).encode()))
    assert refused.value.key == "csv.unit_unread" and refused.value.params == {"unit": unit}
    assert translate("csv.unit_unread", "en", unit=unit).endswith(
        "which GyroLab does not read: convert them to °/h, °/s or rad/s first."
    )


def test_a_long_tables_angles_round_the_other_way_are_used_as_given_and_said(
    student_client, capsys, tmp_path
):
    """A long table's angles are the axis's, clockwise positive (lab-reference §3), and
    each reading is saved at its angle's position -- "0, 90, 180, 270" under the handout's
    counter-clockwise turns puts 90° at position 4.  Students who count the turns made
    write the same numbers, so the preview and ``solve`` say which way they run."""
    from app.cli.main import main

    rows = [
        f"{angle},{value}"
        for angle, value in zip([0, 90, 180, 270], [10.7, 2.8, -9.0, -0.9], strict=True)
        for _ in range(10)
    ]
    text = "angle,reading\n" + "\n".join(rows) + "\n"
    session_id = new_session(student_client)  # counter-clockwise
    page = f"/lab/sessions/{session_id}"

    def preview(text: str) -> dict:
        body = {"part": "heading", "unit": "deg/h", "text": text}
        return post_json(student_client, f"{page}/csv/preview", body, page).json()

    said = preview(text)
    assert [(p["position"], p["angle_deg"]) for p in said["positions"]] == [
        (1, 0),
        (4, 90),
        (3, 180),
        (2, 270),
    ]
    assert said["notes"] == [
        "The file's angles run 0°, 90°, 180°, 270°, round the other way from this session's "
        "positions 1–4 (0°, -90°, -180°, -270°). Angles are used as given, clockwise positive "
        "seen from above, and each reading is saved at the position of its angle; if the "
        "file's angles count the turns made, write them as 0°, -90°, -180°, -270°."
    ]
    turned = (
        text.replace("\n90,", "\n-90,").replace("\n180,", "\n-180,").replace("\n270,", "\n-270,")
    )
    assert preview(turned)["notes"] == []

    path = tmp_path / "long.csv"
    path.write_text(text)
    assert main(["solve", "heading", str(path), "--json"]) == 0
    assert "write them as 0°, -90°, -180°, -270°" in capsys.readouterr().err
    assert main(["solve", "heading", str(path), "--json", "--rotation", "cw"]) == 0
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize(
    ("header", "record"),
    [
        ("时间(s),1,2,3,4", False),  # the handout's numbering beside a time column
        ("t,0°,-90°,-180°,-270°", False),
        ("time_s,position_1,position_2,position_3,position_4", False),
        ("time_s,position,value,x", False),  # the long layout
        ("Time (s),Gyro X,Gyro Y,Gyro Z,Temp", True),  # an IMU's export: one record
    ],
)
def test_a_time_column_beside_numbered_or_named_positions_heads_a_table(header, record):
    from app.core.record_kinds import written_as_a_record

    rows = "".join(f"{0.1 * k:.1f},10.7,2.8,-9.1,-0.9\n" for k in range(5))
    assert written_as_a_record(f"{header}\n{rows}") is record


@pytest.mark.parametrize(
    "text",
    [
        ",".join(f"位置{k}" for k in (1, 2, 3, 4, 4, 3, 2, 1)) + "\n" + "1,2,3,4,5,6,7,8\n" * 3,
        "位置,1,2,3,4,4,3,2,1\n" + ",1,2,3,4,5,6,7,8\n" * 3,
        "".join(f"P{k},{n},{n},{n}\n" for n, k in enumerate((1, 2, 3, 4, 4, 3, 2, 1), start=1)),
    ],
    ids=["named", "numbered", "one row per visit"],
)
def test_the_symmetric_order_named_there_and_back_is_positions_one_to_eight(text):
    """1-2-3-4-4-3-2-1 with each position named again on its second visit: "a position
    named twice" before; the second visits are positions 5-8, as the session numbers them."""
    readings = parse_readings_csv(text)
    assert [v.tolist() for v in readings.positions] == [[float(n)] * 3 for n in range(1, 9)]


@pytest.mark.parametrize(
    "header",
    ["位置1,位置2,位置2,位置1", "位置1,位置2,位置3,位置3", "位置1,位置2,位置3,位置4,位置4"],
)
def test_other_repeated_positions_are_still_refused(header):
    with pytest.raises(UserError) as twice:
        parse_readings_csv(header + "\n" + ",".join(["1"] * (header.count(",") + 1)) + "\n")
    assert twice.value.key == "csv.position_columns"


def test_the_handouts_omega_names_each_positions_column_beside_a_time():
    """ "时间 | ω1 | ω2 | ω3 | ω4": the handout writes ω1 … ω4 for the positions' means, and
    students head their columns so. Beside a time column the header was taken for an
    IMU's record of four axes (before that, the times were position 1)."""
    from app.core.record_kinds import written_as_a_record

    columns = list(handout("handout_horizontal.csv").values())
    text = "时间(s),ω1,ω2,ω3,ω4\n" + "".join(
        f"{0.1 * i:.1f}," + ",".join(f"{c[i]:.2f}" for c in columns) + "\n" for i in range(10)
    )
    assert not written_as_a_record(text)
    assert [v.tolist() for v in parse_readings_csv(text).positions] == columns


@pytest.mark.parametrize(
    "text",
    ["位置1,位置400\n1,2\n", "位置1,1,2\n位置99999999999999999999,3,4\n", "P1：1 2\nP361：3 4\n"],
)
def test_a_position_numbered_past_the_turntables_is_refused_in_every_layout(text):
    """The long layout refused a position past 360; a wide or turned table's was read,
    and previewed at an angle of 9e+21°."""
    with pytest.raises(UserError) as refused:
        parse_readings_csv(text)
    assert refused.value.key == "csv.position_number"


@pytest.mark.one_backend  # the preview's check, not the database's
def test_the_preview_refuses_a_position_the_session_has_not_as_the_save_does(student_client):
    from tests.factories import new_session, post_json

    session_id = new_session(student_client)
    page = f"/lab/sessions/{session_id}"
    body = {"part": "heading", "unit": "deg/h", "text": "P1,P2,P3,P5\n" + "1,2,3,4\n" * 10}
    for path in ("/csv/preview", "/csv"):
        refused = post_json(student_client, page + path, body, page)
        assert refused.status_code == 400 and refused.json()["key"] == "lab.needs_symmetric"


@pytest.mark.parametrize(
    ("header", "said"),
    [
        ("P1,P2,P3,P4,x", [("csv.column_left_out", {"column": "x"})]),
        ("ω1,ω2,ω3,ω4,note", [("csv.column_left_out", {"column": "note"})]),
        ("value,ω1", [("csv.column_left_out", {"column": "value"})]),
        ("位置1,位置2,位置3,位置4,平均", [("csv.summary_column_skipped", {"label": "平均"})]),
        ("位置,1,2,3,4,平均值", [("csv.summary_column_skipped", {"label": "平均值"})]),
        ("sample,position_1,position_2,position_3,position_4", []),  # the readings' numbers
        ("时间(s),1,2,3,4", []),  # the times
        ("position_1,position_2,position_3,position_4,remarks", []),  # words: no readings
    ],
)
def test_a_column_of_numbers_beside_the_positions_is_never_dropped_without_a_word(header, said):
    """A wide table's column that names no position was left out of the readings, and the
    preview, the lab page and ``gyrolab solve`` said nothing: a fifth position headed "x",
    the numbers under "value".  It is said now, as a summary column is; the readings' own
    numbers (1, 2, 3 … under "位置" or "sample"), times and remarks are no readings and go
    unsaid."""
    width = len(header.split(","))
    rows = []
    for k in range(10):
        cells = [f"{10 + 0.1 * k + j:.2f}" for j in range(width)]
        if header.startswith(("位置,", "sample,")):
            cells[0] = str(k + 1)
        if header.endswith("remarks"):
            cells[-1] = "ok" if k % 2 else ""
        rows.append(",".join(cells))
    readings = parse_readings_csv(header + "\n" + "\n".join(rows) + "\n")
    assert readings.layout_notes == said
    for language in ("en", "zh-CN"):
        for key, params in said:
            assert translate(key, language, **params) != key
