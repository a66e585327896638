"""Tables as students make them from the handout: its own header "位置 | 1 | 2 | 3 | 4" with
a label column and a last row of means, columns named by the turntable's angle or "P1",
the table turned on its side -- each read as the positions it holds, the means passed over
and said."""

from __future__ import annotations

import numpy as np
import pytest

from app.core.exceptions import UserError
from app.core.readings import parse_readings_csv
from app.core.table_headers import column_name, numbered_columns, summary_label
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
