"""Static records as loggers write them: a clock for the time ("2026-11-28 23:59:59.900",
ISO 8601, a time of day that runs past midnight), a time in milliseconds, a spreadsheet's
empty last column -- read to the same times and the same analysis as a record with
``time_s``."""

from __future__ import annotations

import datetime as dt
import io
import math

import numpy as np
import pytest

from app.core.allan import analyse_record
from app.core.exceptions import UserError
from app.core.static_record import StaticRecord, read_static_record
from app.core.text_files import text_lines
from tests.noise_sources import static_record

RATES = [10.0346, 10.0822, 9.9512, 10.0078]


def read(text: str) -> StaticRecord:
    return read_static_record(text_lines(text.encode()))


def stamped(format_line, start: dt.datetime, step_s: float = 0.1) -> list[str]:
    return [
        format_line(start + dt.timedelta(seconds=k * step_s), rate) for k, rate in enumerate(RATES)
    ]


LATE = dt.datetime(2026, 11, 28, 23, 59, 59, 800_000)  # the record runs past midnight


@pytest.mark.parametrize(
    "lines",
    [
        ["time,value", *stamped(lambda t, r: f"{t:%Y-%m-%d %H:%M:%S.%f},{r}", LATE)],
        ["timestamp,rate", *stamped(lambda t, r: f"{t:%Y-%m-%dT%H:%M:%S.%f}Z,{r}", LATE)],
        ["datetime;rate", *stamped(lambda t, r: f"{t:%Y/%m/%d %H:%M:%S,%f};{r}", LATE)],
        stamped(lambda t, r: f"{t:%Y-%m-%d %H:%M:%S.%f}  {r}", LATE),  # spaces, no header
        stamped(lambda t, r: f"{t:%Y-%m-%d %H:%M:%S.%f},{r}", LATE),  # no header
        ["Date Time Rate", *stamped(lambda t, r: f"{t:%Y-%m-%d %H:%M:%S.%f} {r}", LATE)],
        ["time,value", *stamped(lambda t, r: f"{t:%H:%M:%S.%f},{r}", LATE)],  # time of day
        ["时间,value", *stamped(lambda t, r: f"{t:%H:%M:%S.%f},{r}", LATE)],
        ["time_ms,value", *(f"{k * 100},{r}" for k, r in enumerate(RATES))],
        ["时间,角速度", *stamped(lambda t, r: f"{t:%Y年%m月%d日 %H:%M:%S.%f},{r}", LATE)],
        ["时间,角速度", *stamped(lambda t, r: f"{t:%Y年%m月%d日%H时%M分%S.%f秒},{r}", LATE)],
        ["Zeit;Wert", *stamped(lambda t, r: f"{t:%d.%m.%Y %H:%M:%S,%f};{r}", LATE)],
        ["time,value", *stamped(lambda t, r: f"{t:%m/%d/%Y %I:%M:%S.%f %p},{r}", LATE)],
        ["time,value", *stamped(lambda t, r: f"{t:%d/%m/%Y %H:%M:%S.%f},{r}", LATE)],
        [
            "时间,value",
            *stamped(
                lambda t, r: (
                    f"{t:%Y/%m/%d} {'下午' if t.hour >= 12 else '上午'} "
                    f"{t.hour % 12 or 12}:{t:%M:%S.%f},{r}"
                ),
                LATE,
            ),
        ],
    ],
    ids=[
        "date-time",
        "iso-z",
        "slashes-semicolons-decimal-comma",
        "spaces",
        "no-header",
        "date-and-time-columns",
        "time-of-day",
        "chinese-name",
        "milliseconds",
        "chinese-date",
        "chinese-hours-minutes-seconds",
        "german-day-first",
        "us-twelve-hour",
        "day-first-slashes",
        "chinese-twelve-hour",
    ],
)
def test_a_loggers_clock_is_read_as_seconds_from_the_first_reading(lines):
    record = read("\n".join(lines) + "\n")
    assert record.values.tolist() == RATES
    np.testing.assert_allclose(record.times_s, [0.0, 0.1, 0.2, 0.3], atol=1e-9)


def test_a_spreadsheets_empty_last_column_is_no_column():
    assert read("".join(f"{r},\n" for r in RATES)).values.tolist() == RATES
    assert read("".join(f"{r};\n" for r in RATES)).values.tolist() == RATES
    with pytest.raises(UserError) as missing:
        read("0,1.5\n0.1,\n0.2,1.7\n")  # an empty value inside is still a bad line
    assert missing.value.key == "allan.bad_line" and missing.value.params["line"] == 2


@pytest.mark.parametrize("bad", ["2026-13-28 10:00:00.2", "yesterday", "10:61:00"])
def test_a_stamp_that_is_no_time_is_named_by_its_line(bad):
    with pytest.raises(UserError) as error:
        read(f"time,value\n2026-11-28 10:00:00.1,1.0\n{bad},2.0\n")
    assert error.value.key == "allan.bad_line" and error.value.params["line"] == 3


def test_a_stamped_record_gives_the_analysis_of_the_same_record_in_seconds():
    """An hour at 10 Hz from the independent generator, 2 s of it lost, written once with
    time_s and once with a logger's clock across midnight: the same gaps found, the same
    rate, the same Allan terms."""
    rates = static_record(1.0, 10.0, arw=0.012, seed=7)
    keep = np.ones(rates.size, bool)
    keep[9000:9020] = False
    seconds = (np.arange(rates.size) / 10.0)[keep]
    kept = rates[keep]
    start = dt.datetime(2026, 11, 28, 23, 30)
    clock = "\n".join(
        f"{start + dt.timedelta(seconds=float(t)):%Y-%m-%d %H:%M:%S.%f},{r:.17g}"
        for t, r in zip(seconds, kept, strict=True)
    )
    plain = "\n".join(f"{t:.17g},{r:.17g}" for t, r in zip(seconds, kept, strict=True))
    by_clock = analyse_record(read("time,value\n" + clock), None)
    by_seconds = analyse_record(read("time_s,value\n" + plain), None)
    assert by_clock.notes == by_seconds.notes
    assert by_clock.samples == by_seconds.samples and by_clock.rate_hz == pytest.approx(10.0)
    assert by_clock.arw_deg_rt_h == pytest.approx(by_seconds.arw_deg_rt_h, rel=1e-9)


@pytest.mark.parametrize(
    "text",
    [
        "0.0 10.0346\n0.1  10.0822\n",
        "time_s value\n0.0 10.0346\n0.1 10.0822\n",
        "# gyro\n0.0\t10.0346\n0.1\t10.0822\n",
    ],
)
def test_one_positions_record_with_spaces_between_its_columns(text):
    """What a script sends the API for one position: "0.1  10.74" per line was one cell,
    taken for a header, then refused on line 2."""
    from app.core.position_records import parse_position_csv

    values, times = parse_position_csv(text)
    assert values.tolist() == RATES[:2] and times.tolist() == [0.0, 0.1]


def test_a_clock_that_ticks_by_the_second_under_readings_at_ten_hertz():
    """A serial logger stamping each line to the whole second, 10 readings a second (the
    record starts and ends mid-second, and loses three seconds once): the rate is counted
    from the readings between ticks, the longest stretch without a missed tick analysed."""
    rng = np.random.default_rng(5)
    start = dt.datetime(2026, 11, 28, 9, 59, 59)
    stamps = [start + dt.timedelta(seconds=k // 10) for k in range(4, 10 * 900)]
    stamps = [
        t
        for t in stamps
        if not (start + dt.timedelta(seconds=100) <= t < start + dt.timedelta(seconds=103))
    ]
    rates = rng.normal(0.0, 0.3, len(stamps)).tolist()
    text = "time,value\n" + "".join(
        f"{t:%H:%M:%S},{r!r}\n" for t, r in zip(stamps, rates, strict=True)
    )
    result = analyse_record(read(text), None)
    assert result.rate_hz == pytest.approx(10.0, rel=1e-9)
    notes = {note["key"]: note["params"] for note in result.notes}
    assert notes["allan.note_coarse_clock"]["tick"] == "1"
    assert notes["allan.note_gaps"] == {"gaps": 1, "missing": 30, "kept": 7970, "seconds": 797}
    # white noise of 0.3 °/h per reading at 10 Hz: N = 0.3 · √(0.1 s / 3600 s/h) °/√h
    assert result.arw_deg_rt_h == pytest.approx(0.3 * math.sqrt(0.1 / 3600.0), rel=0.06)


def test_a_fine_clocks_first_stamp_written_twice_is_not_a_coarse_clock():
    """A FOG logger's file as its tool writes it: a '#date' line, no header, "t, rate, 0"
    at 0.0104 s, and the first stamp (0.00000) written twice.  The one tie was read as a
    clock ticking more slowly than the readings; it is a stamp written twice, said as such,
    the rate taken from the steps."""
    rng = np.random.default_rng(11)
    rates = rng.normal(0.0, 0.05, 20_000)
    times = [0.0, *(0.0104 * k for k in range(rates.size - 1))]
    text = "#2021-03-02 16:56:54\n" + "".join(
        f"{t:.5f}, {r:.5f}, 0.00000\n" for t, r in zip(times, rates, strict=True)
    )
    record = read(text)
    assert record.temperatures_c is None  # the third column's zeros: no sensor's reading
    result = analyse_record(record, None)
    assert result.rate_hz == pytest.approx(1 / 0.0104, rel=1e-6)
    notes = {note["key"]: note["params"] for note in result.notes}
    assert "allan.note_coarse_clock" not in notes
    assert notes["allan.note_tied_stamps"] == {"n": 1}
    # white noise of 0.05 °/h per reading: N = 0.05 · √(0.0104 s / 3600 s/h) °/√h
    assert result.arw_deg_rt_h == pytest.approx(0.05 * math.sqrt(0.0104 / 3600.0), rel=0.05)


def sparrow_lines(count: int, first_column) -> str:
    """A PIG logger's file: a '#date' line, no header, "t, rate, loop error, °C" with the
    rate quantised to 0.00049 °/s and the clock stepping 10.0 or 10.1 ms."""
    rng = np.random.default_rng(3)
    rates = np.round(rng.normal(0.0002, 0.00045, count) / 0.00049) * 0.00049
    loop = rng.integers(-6, 139, count)
    return "#2022-01-27 20:10:44\n" + "".join(
        f"{first_column(k)}, {rate:.5f}, {error}, 35.5\n"
        for k, (rate, error) in enumerate(zip(rates, loop, strict=True))
    )


def test_a_bare_record_of_four_columns_keeps_its_times_when_the_rates_are_chosen():
    """Four columns, none named, the rates chosen as column 2: the first column, which
    rises, is the times (it was dropped, and the analysis asked for the rate)."""
    steps = np.where(np.arange(30_000) % 3 == 0, 0.0100, 0.0101)
    times = 0.6139 + np.concatenate([[0.0], np.cumsum(steps[:-1])])
    record = read_static_record(
        text_lines(sparrow_lines(times.size, lambda k: f"{times[k]:.5f}").encode()), column="2"
    )
    assert record.times_s is not None
    assert record.times_s[:3] == pytest.approx([0.6139, 0.6239, 0.6340])
    assert [note["key"] for note in record.notes] == ["allan.note_first_column_times"]
    result = analyse_record(record, None)
    # the clock's mean step (0.0100 once in three, else 0.0101), not its median (0.0101)
    assert result.rate_hz == pytest.approx((times.size - 1) / (times[-1] - times[0]), rel=1e-9)
    assert result.rate_hz == pytest.approx(3 / 0.0302, rel=1e-4)


def test_a_first_column_that_rises_then_wraps_is_no_time_column():
    """A counter 0…255 that wraps is not times: the rate must be given, as before."""
    record = read_static_record(
        text_lines(sparrow_lines(1_200, lambda k: str(k % 256)).encode()), column="2"
    )
    assert record.times_s is None and record.notes == []
    with pytest.raises(UserError) as refused:
        analyse_record(record, None)
    assert refused.value.key == "allan.no_rate"


def test_a_rate_beside_a_status_flag_is_the_rate_without_times():
    """A KVH DSP-3000 writes "rate  1" per line (CRLF), the 1 its valid flag: the rate
    column was read as times and the flag as rates, refused as "times do not increase"."""
    rng = np.random.default_rng(2)
    rates = rng.normal(0.0012, 0.0004, 6_000)
    text = "".join(f"{rate: .7f}    1\r\n" for rate in rates)
    record = read(text)
    assert record.times_s is None
    assert record.values.tolist() == [float(f"{rate:.7f}") for rate in rates]
    result = analyse_record(record, 100.0)
    assert result.arw_deg_rt_h == pytest.approx(0.0004 * math.sqrt(0.01 / 3600.0), rel=0.06)


def test_a_spreadsheets_date_numbers_are_read_as_days():
    """A time column saved from Excel as numbers: days since 1899-12-30 ("46354.58339…"
    is 2026-11-28 14:00:05).  Read as seconds they gave a rate of 864,000 Hz; as days,
    10 Hz, said."""
    start = (dt.datetime(2026, 11, 28, 14, 0, 5) - dt.datetime(1899, 12, 30)).total_seconds()
    rng = np.random.default_rng(4)
    rates = rng.normal(10.0, 0.5, 3_000)
    text = "time,rate\n" + "".join(
        f"{(start + 0.1 * k) / 86_400:.10f},{rate:.5f}\n" for k, rate in enumerate(rates)
    )
    record = read(text)
    assert record.times_s[:3] == pytest.approx([0.0, 0.1, 0.2], abs=1e-5)  # 10 digits: 8.6 µs
    assert [note["key"] for note in record.notes] == ["allan.note_spreadsheet_days"]
    assert analyse_record(record, None).rate_hz == pytest.approx(10.0, rel=1e-6)
    # stamped to the whole second at 10 Hz: ten readings tie before the first rise
    whole = "time,rate\n" + "".join(
        f"{(start + k // 10) / 86_400:.10f},{rate:.5f}\n" for k, rate in enumerate(rates)
    )
    result = analyse_record(read(whole), None)
    assert result.rate_hz == pytest.approx(10.0, rel=1e-6)
    assert "allan.note_coarse_clock" in {note["key"] for note in result.notes}


@pytest.mark.parametrize(
    "first_times",
    [
        "45000.0\n45000.1\n",  # seconds of the day at 10 Hz (12:30:00.0 on)
        "45000.000\n45000.001\n",  # … at 1 kHz
        "86400.5\n86400.50001\n",  # past the spreadsheets' range: seconds
    ],
)
def test_seconds_that_look_like_date_numbers_stay_seconds(first_times):
    """Seconds of the day step by a millisecond or more: not days."""
    record = read("time,rate\n" + "".join(f"{t},{k}\n" for k, t in enumerate(first_times.split())))
    assert record.times_s[0] == float(first_times.split()[0]) and record.notes == []


@pytest.mark.parametrize(
    "header",
    [
        "采样点,输出值",  # a teaching gyro's program: sample number, output
        "点数,陀螺输出",
        "序号,读数",
        "Sample #,gyro output",
        "采样点,数据",  # the value's name unknown: the counter is still no time
        "index,data",
    ],
)
def test_a_column_that_numbers_the_readings_is_not_their_times(header):
    """A 10 Hz record numbered 1, 2, 3…: the numbers were read as seconds (1 Hz, N off by
    √10) where the header's names were not known; they are no times, so the rate is asked."""
    text = header + "\n" + "".join(f"{k + 1},{10.0 + 0.01 * (k % 7)}\n" for k in range(100))
    record = read(text)
    assert record.times_s is None
    assert record.values[:2].tolist() == [10.0, 10.01]
    with pytest.raises(UserError) as refused:
        analyse_record(record, None)
    assert refused.value.key == "allan.no_rate"


def test_unknown_names_beside_rising_times_keep_their_times():
    record = read("time,data\n0.1,10.5\n0.2,10.6\n0.3,10.4\n")
    assert record.times_s.tolist() == [0.1, 0.2, 0.3] and record.values[0] == 10.5


def test_a_clock_that_runs_back_is_still_refused():
    """Tied stamps are let through, a clock that runs back is not."""
    back = "time,value\n0.0,1\n0.1,2\n0.2,3\n0.15,4\n" + "".join(
        f"{0.3 + 0.1 * k:.1f},{k}\n" for k in range(40)
    )
    with pytest.raises(UserError) as refused:
        analyse_record(read(back), None)
    assert refused.value.key == "allan.bad_times"


def test_one_positions_record_stamped_to_the_second_at_two_hertz():
    """Two readings share each whole-second stamp: the record is read, its times spread
    over each second (each moved by less than its tick), not refused as "not rising"."""
    from app.core.one_position_records import parse_one_position_record

    start = dt.datetime(2026, 11, 28, 14, 0, 0)
    lines = [
        f"{start + dt.timedelta(seconds=k // 2):%Y年%m月%d日 %H:%M:%S},{10 + k}" for k in range(8)
    ]
    parsed = parse_one_position_record("时间,角速度\n" + "\n".join(lines), "deg/h")
    [times] = parsed.readings.times_s
    assert parsed.readings.positions[0].tolist() == [10 + k for k in range(8)]
    np.testing.assert_allclose(times, [0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5])


@pytest.mark.parametrize(
    ("last", "said"),
    [
        ("0.4,", "0.4,"),  # the line cut where the logger stopped writing
        ("0.", "0."),
        ("End of log", "End of log"),  # a closing remark
        ("----------", "----------"),
        (
            "Logger stopped by the user at the end of the run",
            "Logger stopped by the user at the end o…",
        ),
    ],
)
@pytest.mark.parametrize("header", ["time_s,value\n", ""])
def test_a_last_line_cut_off_or_a_closing_remark_is_left_out_and_said(header, last, said):
    """A logger stopped (or unplugged) mid-line leaves its last line cut; some write a
    closing remark.  The readings before are read, the line left out with a note that
    quotes it -- a record of hours is not refused for its last line.  A last line that is a
    whole reading with a bad number (in a record of one column, any line), or a bad line
    before the last, is still refused.  (A line cut inside its last number, "0.4,1" of
    "0.4,10.0", reads as a number: it cannot be told.)"""
    readings = "".join(f"{k / 10:.1f},{rate}\n" for k, rate in enumerate(RATES))
    record = read(header + readings + last + "\n\n")
    np.testing.assert_allclose(record.values, RATES)
    np.testing.assert_allclose(record.times_s, [0.0, 0.1, 0.2, 0.3])
    line = len(RATES) + 1 + bool(header)
    left_out = [n for n in record.notes if n["key"] == "allan.note_last_line_left_out"]
    assert left_out == [
        {"key": "allan.note_last_line_left_out", "params": {"line": line, "text": said}}
    ]
    # power lost mid-line: the rest of the file's space left as NUL bytes
    lost = read_static_record(text_lines((header + readings + last).encode() + bytes(5000)))
    np.testing.assert_allclose(lost.values, RATES)
    assert [n for n in lost.notes if n["key"] == "allan.note_last_line_left_out"] == left_out
    for refused, bad in ((readings + "0.4,abc\n", 5), (readings[:9] + "\n" + readings[9:], 2)):
        with pytest.raises(UserError) as error:
            read(header + refused)
        assert error.value.key == "allan.bad_line"
        assert error.value.params["line"] == bad + bool(header)
    with pytest.raises(UserError) as error:
        read("".join(f"{rate}\n" for rate in RATES) + "oops\n")
    assert (error.value.key, error.value.params["line"]) == ("allan.bad_line", 5)


def test_a_file_ending_in_half_a_character_loses_nothing():
    """A record whose last byte is a Windows-1252 accent ("José" with no line end) is no
    GB18030 (a lead byte with nothing after it): read as Windows-1252, whole -- it lost its
    last character.  A long record cut mid-character (a logger that lost power) keeps its
    last line but for the half character."""
    assert list(text_lines("time_s,value\n# José".encode("cp1252"))) == ["time_s,value", "# José"]
    long = ("time_s,value\n" + "0.1,10.00\n" * 20_000).encode() + "# 记录".encode("gb18030")
    assert list(text_lines(long, chunk=4096))[-1] == "# 记录"
    assert list(text_lines(long[:-1], chunk=4096))[-1] == "# 记"


@pytest.mark.parametrize(
    ("encoding", "remark"),
    [("cp1252", "# stopped at 25 °C"), ("gb18030", "# 记录结束，25 °C"), ("utf-8", "# 结束 °C")],
)
def test_a_first_non_ascii_byte_past_the_first_block_chooses_the_encoding(encoding, remark):
    """A long logger record whose first MiB is ASCII and whose last lines say "°C" in its
    own encoding: read whole.  Before, the first block chose UTF-8 and the record was
    refused as "not text" at the remark."""
    readings = "".join(f"{k / 10:.1f},{10 + (k % 7) * 0.01:.2f}\n" for k in range(30_000))
    data = ("time_s,value\n" + readings).encode() + f"{remark}\n3000.0,10.00\n".encode(encoding)
    chunk = 64 << 10  # the remark some blocks past the first
    assert data.index(b"# ") > 4 * chunk
    lines = list(text_lines(data, chunk=chunk))
    assert lines[-1] == "3000.0,10.00" and len(lines) == 30_003
    assert remark in lines  # cp1252's "°C" (0xB0 0x43) is GB18030 too, but no GB2312
    record = read_static_record(text_lines(data, chunk=chunk))
    assert record.values.size == 30_001
    with pytest.raises(UserError):  # bytes of no text at all are still refused
        list(text_lines(data + b"\xff\xfe\x00\x81\x00", chunk=chunk))


@pytest.mark.parametrize(
    ("header", "unit", "scale"),
    [
        ("时间/s,陀螺输出/(°/h),温度/℃", "deg/h", 1.0),  # GB 3101: quantity/unit
        ("t/s,ω/(°/s)", "deg/s", 1.0),
        ("时间/ms,角速率/(°/h)", "deg/h", 1e3),
        ("序号,时间/s,角速率/°/h", "deg/h", 1.0),  # a counter first, the unit unbracketed
        ("time/(s),rate/dps", "deg/s", 1.0),
    ],
)
def test_a_header_that_writes_quantity_over_unit_as_chinese_tables_do(header, unit, scale):
    """ISO 80000-1 and China's GB 3101 head a table's column "quantity/unit": "时间/s" was
    no time column, so a Chinese logger's record was asked for its sample rate, and
    "温度/℃" no temperature.  A bare unit ("°/h") is still a name."""
    counter = header.startswith("序号")
    rows = [
        (f"{k + 1}," if counter else "")
        + f"{k * 0.1 * scale:g},{rate}"
        + (",25.5" if "温度" in header else "")
        for k, rate in enumerate(RATES)
    ]
    for encoding in ("utf-8", "gb18030"):
        text = (header + "\n" + "\n".join(rows) + "\n").encode(encoding)
        record = read_static_record(text_lines(text))
        assert record.times_s == pytest.approx([0.0, 0.1, 0.2, 0.3]), (header, encoding)
        assert record.values.tolist() == RATES and record.unit == unit
        if "温度" in header:
            assert record.temperatures_c.tolist() == [25.5] * 4
    bare = read("°/h\n" + "\n".join(str(rate) for rate in RATES) + "\n")
    assert bare.values.tolist() == RATES and bare.times_s is None


@pytest.mark.parametrize(
    ("preamble", "key"),
    [
        (["Device: DSP-1750", "Serial: 123456", "Date: 2026-11-28 14:00", "Sample rate: 2 Hz", ""],
         "allan.note_about_the_record"),
        (["采样率：2 Hz", "设备：光纤陀螺 FOG-50"], "allan.note_about_the_record"),
        (["Operator: Zhang San"], "allan.note_about_it"),
    ],
)  # fmt: skip
def test_a_loggers_lines_about_the_record_above_its_table_are_passed_over_and_said(preamble, key):
    """A logger's export that opens with lines about the record ("Device: DSP-1750",
    "Sample rate: 2 Hz", "采样率：2 Hz") and then its table, columns aligned by spaces:
    "line 3 of the record is not a reading" before, as the first line set the columns."""
    from app.web.i18n import translate

    rates = static_record(1.0, 2.0, arw=0.01, seed=8)
    table = ["Time(s)      Rate(deg/h)    Temp(C)"]
    table += [f"{k / 2:10.1f}   {rate:12.5f}   {25.0:7.2f}" for k, rate in enumerate(rates)]
    record = read("\n".join(preamble + table) + "\n")
    assert record.times_s[:3].tolist() == [0.0, 0.5, 1.0]
    assert record.values == pytest.approx(rates, abs=1e-5)
    assert record.temperatures_c[0] == 25.0
    said = [note for note in record.notes if note["key"] == key]
    assert said and said[0]["params"]["first"] == 1
    assert said[0]["params"]["text"] == preamble[0]
    for language in ("en", "zh-CN"):
        assert preamble[0] in translate(key, language, **said[0]["params"])
    result = analyse_record(record, None)
    assert result.arw_deg_rt_h == pytest.approx(0.01, rel=0.1)


def test_a_clocks_readings_are_never_taken_for_lines_about_the_record():
    lines = stamped(lambda t, r: f"{t:%Y-%m-%d %H:%M:%S.%f}  {r}", LATE)
    record = read("\n".join(lines) + "\n")
    assert record.values.tolist() == RATES
    assert not [n for n in record.notes if n["key"].startswith("allan.note_about")]


def test_a_sample_rate_the_file_states_above_its_table_is_used_where_nothing_else_gives_one():
    from app.core.record_preamble import stated_rate_hz

    rates = static_record(1.0, 2.0, arw=0.01, seed=9)
    body = "Rate(deg/h)\n" + "".join(f"{rate:.5f}\n" for rate in rates)
    record = read("Device: DSP-1750\n采样率：2 Hz\n\n" + body)
    assert record.times_s is None and record.stated_rate_hz == 2.0
    result = analyse_record(record, None)
    assert result.rate_hz == 2.0 and result.arw_deg_rt_h == pytest.approx(0.01, rel=0.1)
    said = [n for n in result.notes if n["key"] == "allan.note_rate_stated"]
    assert said == [{"key": "allan.note_rate_stated", "params": {"rate": "2"}}]
    assert analyse_record(record, 4.0).rate_hz == 4.0  # a rate given wins, and is not said
    with pytest.raises(UserError) as refused:  # nothing states one: asked, as before
        analyse_record(read(body), None)
    assert refused.value.key == "allan.no_rate"
    assert [stated_rate_hz(t) for t in ("Output rate: 1 kHz", "Rate: 100 sps", "Date: 2 Hz")] == [
        1000.0,
        100.0,
        None,
    ]


def test_a_workbooks_lines_about_the_record_in_two_cells_and_its_stated_rate():
    """An Excel logger's sheet: "Device:" | "DSP-1750" and "Sample rate:" | "2 Hz" in two
    cells each (a CSV's "Device:,DSP-1750"), then the readings without times."""
    from openpyxl import Workbook

    from app.core.workbook_text import workbook_text

    rates = static_record(1.0, 2.0, arw=0.01, seed=4)
    sheet = Workbook()
    rows = sheet.active
    rows.append(["Device:", "DSP-1750"])
    rows.append(["Sample rate:", "2 Hz"])
    rows.append(["Rate (deg/h)"])
    for rate in rates:
        rows.append([float(rate)])
    saved = io.BytesIO()
    sheet.save(saved)
    comma = "Device:,DSP-1750\nSample rate:,2 Hz\nRate (deg/h)\n" + "".join(
        f"{float(rate)!r}\n" for rate in rates
    )
    for text in (workbook_text(saved.getvalue()), comma):
        record = read(text)
        assert record.stated_rate_hz == 2.0 and record.values == pytest.approx(rates)
        result = analyse_record(record, None)
        assert result.rate_hz == 2.0
        assert result.arw_deg_rt_h == pytest.approx(0.01, rel=0.1)
