"""LabVIEW's measurement file (.lvm), as "Write To Measurement File" writes it in a
university lab's data-acquisition program: its headers passed over and said, its X column
read as the times, its Delta_X as the rate where it has no X column, decimal commas, several
segments, several channels (one chosen) -- for a teacher's bench record and for a
student's position alike.  Before, every such file was "line 12 is not a reading"."""

from __future__ import annotations

import io
import math

import numpy as np
import pytest

from app.core.allan import analyse_record
from app.core.exceptions import UserError
from app.core.one_position_records import parse_one_position_record
from app.core.static_record import read_static_record
from app.core.text_files import text_lines
from app.web.i18n import translator
from tests.noise_sources import static_record

ARW = 0.012  # °/√h
RATE_HZ = 10.0


def file_header(decimal: str = ".", x_columns: str = "One") -> list[str]:
    """The file header of NI's format (its fields as LabVIEW 2 writes them), 12 lines."""
    return [
        "LabVIEW Measurement\t",
        "Writer_Version\t2",
        "Reader_Version\t2",
        "Separator\tTab",
        f"Decimal_Separator\t{decimal}",
        "Multi_Headings\tNo",
        f"X_Columns\t{x_columns}",
        "Time_Pref\tRelative",
        "Operator\tlab",
        "Date\t2026/11/20",
        "Time\t14:02:11.4306640625",
        "***End_of_Header***\t",
    ]


def segment_header(count: int, channels: int = 1, start_s: float = 0.0) -> list[str]:
    """A segment header of NI's format (one value per channel), 8 lines."""
    each = "\t".join
    return [
        f"Channels\t{channels}\t",
        "Samples\t" + each([str(count)] * channels) + "\t",
        "Date\t" + each(["2026/11/20"] * channels) + "\t",
        "Time\t" + each(["14:02:11.4306640625"] * channels) + "\t",
        "X_Dimension\t" + each(["Time"] * channels) + "\t",
        "X0\t" + each([f"{start_s:.16E}"] * channels) + "\t",
        "Delta_X\t" + each([f"{1.0 / RATE_HZ:.6f}"] * channels) + "\t",
        "***End_of_Header***\t",
    ]


def lvm(
    values: np.ndarray,
    *,
    decimal: str = ".",
    x_column: bool = True,
    segments: int = 1,
    channels: tuple[str, ...] = ("Untitled",),
    separator: str = "\t",
) -> str:
    lines = file_header(decimal, "One" if x_column else "No")
    for part, chunk in enumerate(np.array_split(values, segments)):
        start = part * len(values) // segments
        lines += [""] + segment_header(chunk.size, len(channels), start / RATE_HZ)
        names = (["X_Value"] if x_column else []) + list(channels) + ["Comment"]
        lines.append("\t".join(names))
        for k, value in enumerate(chunk):
            cells = [f"{(start + k) / RATE_HZ:.6f}"] if x_column else []
            cells += [f"{value + 3.0 * c:.6f}" for c in range(len(channels))]
            lines.append("\t".join(cells).replace(".", decimal))
    text = "\n".join(lines) + "\n"
    if separator != "\t":  # "Separator Comma": every tab of the file a comma
        text = text.replace("Separator\tTab", "Separator\tComma").replace("\t", separator)
    return text


def record() -> np.ndarray:
    return static_record(1.0, RATE_HZ, arw=ARW, seed=11)


def notes_of(result) -> dict:
    return {note["key"]: note["params"] for note in result.notes}


@pytest.mark.parametrize(
    ("options", "rate", "note"),
    [
        ({}, None, "allan.note_labview"),
        ({"decimal": ","}, None, "allan.note_labview"),  # a European Windows
        ({"x_column": False}, None, "allan.note_labview"),  # the rate from Delta_X
        ({"segments": 3}, None, "allan.note_labview_segments"),
        ({"separator": ","}, None, "allan.note_labview"),  # "Separator Comma"
    ],
)
def test_a_labview_record_is_read_and_its_noise_found(options, rate, note):
    values = record()
    read = read_static_record(text_lines(lvm(values, **options).encode()), finite=False)
    assert read.values.size == values.size
    assert read.values == pytest.approx(values, abs=1e-6)
    if options.get("x_column", True):
        assert read.times_s == pytest.approx(np.arange(values.size) / RATE_HZ)
    else:
        assert read.times_s is None and read.stated_rate_hz == RATE_HZ
    result = analyse_record(read, rate)
    assert result.arw_deg_rt_h == pytest.approx(ARW, rel=0.05)
    said = notes_of(result)
    assert said[note]["first"] == 1 and said[note]["last"] == 21  # 12 + blank + 8
    if note == "allan.note_labview_segments":
        assert said[note]["segments"] == 3
        words = translator("en")(note, **said[note])
        assert words == (
            "Read as a LabVIEW measurement file (.lvm) of 3 segments: its headers, lines "
            "1–21 and each later segment's, were passed over."
        )
    else:
        assert translator("en")(note, **said[note]) == (
            "Read as a LabVIEW measurement file (.lvm): its headers, lines 1–21, were passed over."
        )
        assert translator("zh-CN")(note, **said[note]) == (
            "按 LabVIEW 测量文件（.lvm）读取：其文件头（第 1–21 行）已跳过。"
        )
    if not options.get("x_column", True):
        assert said["allan.note_rate_stated"] == {"rate": "10"}


def test_a_labview_record_of_several_channels_asks_which_is_the_gyro():
    values = record()[:3000]
    text = lvm(values, channels=("Gyro X", "Gyro Y", "Gyro Z"))
    with pytest.raises(UserError) as refused:
        read_static_record(io.StringIO(text))
    assert "Gyro X, Gyro Y, Gyro Z" in str(refused.value.params)
    chosen = read_static_record(io.StringIO(text), column="Gyro Z")
    assert chosen.values == pytest.approx(values + 6.0, abs=1e-6)


def test_a_students_position_saved_by_labview_is_read_and_said():
    """The lab page's file of one position (and the API's text/csv): the readings and their
    times, and the headers passed over among the lines said to be left out."""
    values = 8.6 + record()[:600] / 100.0
    read = parse_one_position_record(lvm(values), "deg/h")
    assert read.readings.positions[0] == pytest.approx(values, abs=1e-6)
    assert read.readings.times_s[0] == pytest.approx(np.arange(600) / RATE_HZ)
    assert [note["key"] for note in read.notes] == ["allan.note_labview"]


def test_only_a_file_that_starts_as_labview_writes_it_is_read_so():
    """A record whose preamble mentions LabVIEW further down is read as before."""
    values = record()[:2000]
    text = "Device: FOG bench, logged by LabVIEW Measurement VI\ntime_s,value\n" + "".join(
        f"{k / RATE_HZ:.1f},{v:.6f}\n" for k, v in enumerate(values)
    )
    read = read_static_record(io.StringIO(text))
    assert "allan.note_labview" not in {note["key"] for note in read.notes}
    assert read.values == pytest.approx(values, abs=1e-6)
    assert math.isclose(read.times_s[-1], 199.9)
