"""Static records as IMUs and their tools write them -- EuRoC and Kalibr's CSV (the header
behind '#', times in ns, rates in rad/s named in the header), ROS's ``rostopic echo -p``
(the header behind '%', a frame's name among the numbers), Xsens MT Manager ('//'
comments, tabs, SampleTimeFine in 100 µs ticks, no unit), a spreadsheet's "Time (s)" and
"Rate (deg/s)" -- read and analysed from an independent generator's white noise, whose
angle random walk is known in closed form: N = σ·√Δt."""

from __future__ import annotations

import functools
import gzip
import math

import numpy as np
import pytest

from app.core.allan import analyse_record
from app.core.clock_stamps import TimeColumn, epoch_scale
from app.core.column_names import column_name, rate_unit
from app.core.exceptions import UserError
from app.core.record_columns import header_layout
from app.core.static_record import read_static_record
from app.core.text_files import text_lines
from app.core.units import unit_doubt

RATE_HZ = 100.0
SECONDS = 650.0
SIGMA_DEG_S = 0.004  # white noise per sample, °/s
# N (°/√h) = σ (°/h) · √(Δt in h) = σ (°/s) · 3600 · √(Δt / 3600 s) = σ (°/s) · 60 · √Δt
ARW_DEG_RT_H = SIGMA_DEG_S * 60.0 * math.sqrt(1.0 / RATE_HZ)
EPOCH_NS = 1_403_636_579_758_555_392  # EuRoC's MH_01 starts here


@functools.cache
def white_rates(seed: int = 7, axes: int = 3) -> np.ndarray:
    """Independent of the app's simulator: numpy's own white noise about a small bias, °/s."""
    rng = np.random.default_rng(seed)
    count = int(SECONDS * RATE_HZ)
    return rng.normal(0.0, SIGMA_DEG_S, (count, axes)) + np.array([2e-3, -1e-3, 4e-3])[:axes]


def read(text: str, column: str | None = None):
    return read_static_record(text_lines(text.encode()), column=column)


@functools.cache
def euroc_text() -> str:
    rates = np.radians(white_rates()).tolist()
    step_ns = int(1e9 / RATE_HZ)
    lines = [
        "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
        "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]"
    ]
    lines += [
        f"{EPOCH_NS + k * step_ns},{x},{y},{z},0.01,-0.02,9.81" for k, (x, y, z) in enumerate(rates)
    ]
    return "\n".join(lines) + "\n"


@functools.cache
def ros_text() -> str:
    rates = np.radians(white_rates()).tolist()
    step_ns = int(1e9 / RATE_HZ)
    lines = [
        "%time,field.header.seq,field.header.stamp,field.header.frame_id,"
        "field.angular_velocity.x,field.angular_velocity.y,field.angular_velocity.z"
    ]
    lines += [
        f"{EPOCH_NS + k * step_ns},{k},{EPOCH_NS + k * step_ns},imu_link,{x},{y},{z}"
        for k, (x, y, z) in enumerate(rates)
    ]
    return "\n".join(lines) + "\n"


@functools.cache
def xsens_text() -> str:
    rates = np.radians(white_rates()).tolist()
    lines = [
        "// Start Time: Unknown",
        "// Update Rate: 100.0Hz",
        "// Filter Profile: General",
        "PacketCounter\tSampleTimeFine\tGyr_X\tGyr_Y\tGyr_Z",
    ]
    lines += [
        f"{k}\t{4_000_000 + k * 100}\t{x:.8f}\t{y:.8f}\t{z:.8f}"
        for k, (x, y, z) in enumerate(rates)
    ]
    return "\n".join(lines) + "\n"


def keys(result) -> list[str]:
    return [note["key"] for note in result.notes]


def test_a_euroc_record_header_behind_a_hash_ns_times_rad_per_s():
    record = read(euroc_text(), column="w_RS_S_z")
    assert record.unit == "rad/s"
    # times from a clock in ns, counted from the first reading, exact
    assert record.times_s[:3].tolist() == [0.0, 0.01, 0.02]
    result = analyse_record(record, None)
    assert result.rate_hz == pytest.approx(RATE_HZ, rel=1e-12)
    assert result.arw_deg_rt_h == pytest.approx(ARW_DEG_RT_H, rel=0.05)
    assert keys(result)[:2] == ["allan.note_comment_header", "allan.note_unit_from_header"]
    assert "allan.note_unit_doubt" not in keys(result)


def test_a_euroc_axis_chosen_by_its_full_header_cell_or_its_number():
    by_name = read(euroc_text(), column="w_RS_S_y [rad s^-1]")
    by_number = read(euroc_text(), column="3")
    assert np.array_equal(by_name.values, by_number.values)


def test_a_ros_topic_dump_with_a_frame_name_among_the_numbers():
    record = read(ros_text(), column="field.angular_velocity.z")
    assert record.unit == "rad/s"  # sensor_msgs/Imu: rad/s by definition
    result = analyse_record(record, None)
    assert result.rate_hz == pytest.approx(RATE_HZ, rel=1e-12)
    assert result.arw_deg_rt_h == pytest.approx(ARW_DEG_RT_H, rel=0.05)
    notes = {note["key"]: note["params"] for note in result.notes}
    assert notes["allan.note_time_unit"] == {"unit": "ns", "column": 1}
    assert "allan.note_comment_header" in notes


def test_without_a_column_the_imus_columns_are_listed_by_name():
    with pytest.raises(UserError) as error:
        read(ros_text())
    assert error.value.key == "allan.no_value_column"
    assert "field.angular_velocity.z" in error.value.params["columns"]
    assert "imu_link" not in error.value.params["columns"]


def test_an_xsens_export_no_unit_named_is_doubted_then_read_as_chosen():
    record = read(xsens_text(), column="Gyr_Z")
    assert record.unit is None
    assert record.times_s[1] == pytest.approx(0.01, abs=1e-12)  # SampleTimeFine: 100 µs
    as_deg_h = analyse_record(record, None)
    assert "allan.note_unit_doubt" in keys(as_deg_h)  # rad/s read as °/h: a floor of 1e-7
    as_rad_s = analyse_record(record, None, unit="rad/s")
    assert as_rad_s.arw_deg_rt_h == pytest.approx(ARW_DEG_RT_H, rel=0.05)
    assert "allan.note_unit_doubt" not in keys(as_rad_s)


def test_a_spreadsheets_units_in_parentheses():
    rates = white_rates(axes=1)[:, 0]
    text = "Time (s),Rate (deg/s)\n" + "".join(
        f"{k / RATE_HZ:.2f},{r:.7f}\n" for k, r in enumerate(rates)
    )
    record = read(text)
    assert record.unit == "deg/s"
    result = analyse_record(record, None)
    assert result.arw_deg_rt_h == pytest.approx(ARW_DEG_RT_H, rel=0.05)


def test_a_unit_chosen_against_the_header_is_refused():
    record = read(euroc_text(), column="w_RS_S_x")
    with pytest.raises(UserError) as error:
        analyse_record(record, None, unit="deg/h")
    assert error.value.key == "allan.unit_conflict"
    assert error.value.params == {"header": "rad/s", "chosen": "°/h"}
    same = analyse_record(record, None, unit="rad/s")  # the header's own unit: no conflict
    assert same.arw_deg_rt_h == pytest.approx(ARW_DEG_RT_H, rel=0.05)


def test_many_columns_and_no_header_ask_which_is_the_rate():
    text = "".join(f"{k},0.1,0.2,{k % 7}\n" for k in range(20))
    with pytest.raises(UserError) as error:
        read(text)
    assert error.value.key == "allan.choose_column" and error.value.params == {"count": 4}
    assert read(text, column="4").values[:3].tolist() == [0.0, 1.0, 2.0]
    # the bridge's static record keeps its bare layout: time, rate, case temperature
    bare = read("0.0,1.5,20.1\n0.1,1.6,20.2\n")
    assert bare.values.tolist() == [1.5, 1.6] and bare.temperatures_c.tolist() == [20.1, 20.2]


def test_a_comment_above_bare_numbers_is_no_header_when_its_width_differs():
    record = read("# bench 3, 2026-11-28, FOG at rest, 10 Hz\n1.5\n1.6\n")
    assert record.values.tolist() == [1.5, 1.6] and record.notes == []


@pytest.mark.parametrize(
    ("cell", "base", "unit"),
    [
        ("Time (s)", "time", "s"),
        ("w_RS_S_z [rad s^-1]", "w_rs_s_z", "rad s^-1"),
        ("time_ms", "time", "ms"),
        ("rate_deg_h", "rate", "deg_h"),
        ("rate_deg_s", "rate", "deg_s"),
        ("value", "value", None),
        ("position_2", "position_2", None),
        ("角速度 (°/h)", "角速度", "°/h"),
    ],
)
def test_a_column_name_and_its_unit(cell, base, unit):
    name = column_name(cell)
    assert (name.base, name.unit) == (base, unit)


@pytest.mark.parametrize(
    ("text", "unit"),
    [
        ("rad s^-1", "rad/s"),
        ("rad/s", "rad/s"),
        ("°/s", "deg/s"),
        ("dps", "deg/s"),
        ("deg_h", "deg/h"),
        ("°/h", "deg/h"),
        ("m s^-2", None),
        (None, None),
    ],
)
def test_rate_units_as_headers_write_them(text, unit):
    assert rate_unit(text) == unit


@pytest.mark.parametrize(
    ("first", "told"),
    [
        (0.0, None),
        (1.7e9, None),  # seconds since 1970
        (1.7e12, (1e-3, "ms")),
        (1.7e15, (1e-6, "µs")),
        (1.7e18, (1e-9, "ns")),
    ],
)
def test_a_times_unit_told_by_its_size(first, told):
    assert epoch_scale(first) == told


def test_ns_clock_times_are_exact_across_blocks():
    clock = TimeColumn(None)
    first = clock.seconds(np.array([str(EPOCH_NS), str(EPOCH_NS + 5_000_000)], dtype=object))
    later = clock.seconds(np.array([str(EPOCH_NS + 10_000_000_001)], dtype=object))
    assert first.tolist() == [0.0, 0.005] and later.tolist() == [10.000000001]
    assert clock.inferred == "ns"


def test_the_header_names_the_time_and_temperature_by_their_bases():
    layout = header_layout(["Time [ms]", "Rate (deg/h)", "Temperature (°C)"])
    assert (layout.value, layout.time, layout.temperature) == (1, 0, 2)
    assert layout.time_scale == 1e-3 and layout.rate_unit == "deg/h"


@pytest.mark.parametrize(
    ("floor", "doubted"), [(2e-7, True), (1e-3, False), (50.0, False), (4e4, True)]
)
def test_an_allan_floor_no_gyro_has_doubts_the_unit(floor, doubted):
    assert (unit_doubt(floor) is not None) is doubted


@pytest.mark.one_backend  # the record's reading does not depend on the database
def test_the_teacher_uploads_a_euroc_record_and_a_doubtful_unit_is_asked(app, teacher):
    """Through the assignment page: the EuRoC record gzip-compressed, the unit left to
    the file; the Xsens export, whose header names no unit, refused until it is chosen."""
    from app.db import write_session
    from app.models import Assignment, Role
    from tests.factories import browser, make_course, make_user
    from tests.test_characterisation import shown, stored, upload

    student = make_user("s1", Role.student, name="学生1")
    course_id = make_course(teacher, "Bench lab", (student,))
    with write_session() as db:
        assignment = Assignment(course_id=course_id, title="Bench", latitude_deg=39.93)
        db.add(assignment)
        db.flush()
        world = {"course": course_id, "assignment": assignment.id, "app": app}
    client = browser(world, "teacher1")
    reply = upload(client, world, xsens_text(), rate="", column="Gyr_Z")
    page = shown(client, reply)
    assert "likely in another unit" in page and stored(world) is None
    reply = upload(client, world, xsens_text(), rate="", column="Gyr_Z", unit="rad/s")
    assert stored(world)["arw_deg_rt_h"] == pytest.approx(ARW_DEG_RT_H, rel=0.05)
    packed = gzip.compress(euroc_text().encode())
    reply = upload(client, world, packed, rate="", column="w_RS_S_z")
    summary = stored(world)
    assert summary["rate_hz"] == pytest.approx(RATE_HZ)
    assert summary["arw_deg_rt_h"] == pytest.approx(ARW_DEG_RT_H, rel=0.05)
    page = shown(client, reply)
    assert "as the record&#39;s header says" in page or "as the record's header says" in page
    reply = upload(client, world, packed, rate="", column="w_RS_S_z", unit="deg/s")
    page = shown(client, reply)
    assert "header gives the rates in rad/s, but °/s was chosen" in page


def angles_text(header: str, angles_per_unit: float, integrated: bool, times: bool) -> str:
    """Angles per output from the same white rates: each output's increment ω·Δt, or
    their running sum, in the header's unit (``angles_per_unit`` of it per degree)."""
    rates = white_rates(axes=1)[:, 0] + 15.0 / 3600.0  # °/s, with Earth's rate in it
    degrees = rates / RATE_HZ
    if integrated:
        degrees = np.cumsum(degrees)
    values = (degrees * angles_per_unit).tolist()
    rows = (f"{k / RATE_HZ:.2f},{v!r}" if times else repr(v) for k, v in enumerate(values))
    return header + "\n" + "\n".join(rows) + "\n"


@pytest.mark.parametrize(
    ("header", "per_degree", "integrated", "times", "told"),
    [
        ("time_s,dtheta_z [rad]", math.pi / 180.0, False, True, False),
        ("time_s,Delta angle (deg)", 1.0, False, True, False),
        ("time_s,angle (deg)", 1.0, True, True, True),  # the readings tell the kind
        ("integrated_angle [arcsec]", 3600.0, True, False, False),
        ("gyro_z [µrad]", math.pi / 180.0 * 1e6, False, False, True),
    ],
)
def test_angles_per_output_become_rates(header, per_degree, integrated, times, told):
    record = read(angles_text(header, per_degree, integrated, times))
    result = analyse_record(record, None if times else RATE_HZ)
    assert result.arw_deg_rt_h == pytest.approx(ARW_DEG_RT_H, rel=0.05)
    assert result.samples == int(SECONDS * RATE_HZ) - integrated
    kind = "integrated" if integrated else "increment"
    assert f"allan.note_angle_{kind}" in keys(result)
    assert ("allan.note_angle_told" in keys(result)) is told
    assert "allan.note_unit_doubt" not in keys(result)


def test_increments_from_a_clock_that_jitters_by_a_tick_keep_their_mean_rate():
    """Increments of a steady 15 °/h over a clock stepping 10.0 or 10.1 ms: × the mean
    rate (1 / 10.067 ms) they give 15 °/h; × the median step's rate (1 / 10.1 ms) 0.33 %
    less, the error a real logger's jitter put into every rate."""
    from app.core.angle_outputs import rates_from_angles
    from app.core.record_checks import sample_rate_hz

    steps = np.where(np.arange(3_000) % 3 == 0, 0.0100, 0.0101)
    times = np.concatenate([[0.0], np.cumsum(steps)])
    increments = 15.0 / 3600.0 * steps  # degrees turned over each output's own interval
    text = "time_s,dtheta_z [deg]\n" + "".join(
        f"{t:.4f},{float(d)!r}\n" for t, d in zip(times[1:], increments, strict=True)
    )
    record = read(text)
    assert sample_rate_hz(record.times_s) == pytest.approx(2_999 / (times[-1] - times[1]))
    rates, _ = rates_from_angles(record, record.angle, None)
    assert float(np.mean(rates.values)) == pytest.approx(15.0, rel=1e-4)


def test_the_sample_rate_leaves_out_gaps_and_tied_stamps():
    """f = kept steps / their sum: a gap of five steps and a stamp written twice change
    neither the count nor the sum."""
    from app.core.record_checks import sample_rate_hz

    times = np.concatenate([[0.0, 0.0], 0.01 * np.arange(1, 50), 0.01 * np.arange(55, 90)])
    assert sample_rate_hz(times) == pytest.approx(100.0, rel=1e-12)
    assert math.isnan(sample_rate_hz(np.zeros(5)))


def test_a_rate_unit_chosen_for_angles_is_refused():
    record = read(angles_text("time_s,dtheta_z [rad]", math.pi / 180.0, False, True))
    with pytest.raises(UserError) as error:
        analyse_record(record, None, unit="rad/s")
    assert error.value.key == "allan.angle_not_rate" and error.value.params == {"unit": "rad"}


def test_the_kind_of_angle_told_from_the_readings():
    from app.core.angle_outputs import angle_kind

    increments = np.random.default_rng(3).normal(1e-4, 1e-5, 1000)
    assert angle_kind(increments) == "increment"
    assert angle_kind(np.cumsum(increments)) == "integrated"
    # a random walk alone (no ramp): still told, ρ ≈ √(6/n)
    assert angle_kind(np.cumsum(increments - 1e-4)) == "integrated"


@pytest.mark.parametrize(
    ("cell", "kind"),
    [
        ("dtheta_z [rad]", "increment"),
        ("Delta angle (deg)", "increment"),
        ("gyro_d_ang_x [rad]", "increment"),
        ("integrated_angle [arcsec]", "integrated"),
        ("角增量 (°)", "increment"),
        ("angle (deg)", None),
        ("gyro_z [rad/s]", "rate"),
    ],
)
def test_what_an_angle_columns_name_says(cell, kind):
    from app.core.column_names import angle_output

    angle = angle_output(column_name(cell))
    assert (angle.kind if angle else "rate") == kind


def test_names_with_units_over_columns_split_by_spaces():
    text = "Time (s)  Rate (deg/s)\n0.00  0.0042\n0.01  0.0040\n0.02  0.0041\n"
    record = read(text)
    assert record.unit == "deg/s" and record.times_s.tolist() == [0.0, 0.01, 0.02]
    with pytest.raises(UserError) as error:  # names that cannot match the columns
        read("a b c d e\n0.00  0.0042\n")
    assert error.value.key == "allan.bad_line" and error.value.params == {"line": 2}


def test_the_one_column_with_a_rates_unit_is_the_rate():
    layout = header_layout(["time_ns", "gyro_z [rad/s]", "temp"])
    assert (layout.value, layout.time, layout.temperature) == (1, 0, 2)
    assert layout.rate_unit == "rad/s" and layout.time_scale == 1e-9
    with pytest.raises(UserError) as error:  # two such columns: which one is not told
        header_layout(["t", "gx [rad/s]", "gy [rad/s]", "gz [rad/s]"])
    assert error.value.key == "allan.no_value_column"


@pytest.mark.parametrize(
    ("header", "offered"),
    [
        (  # EuRoC / Kalibr: the gyro's three axes, not the accelerometer's
            "timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
            "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]",
            ["w_RS_S_x [rad s^-1]", "w_RS_S_y [rad s^-1]", "w_RS_S_z [rad s^-1]"],
        ),
        (  # ROS: not the header's sequence number, stamp or frame, nor the orientation
            "time,field.header.seq,field.header.stamp,field.header.frame_id,"
            "field.orientation.x,field.angular_velocity.x,field.angular_velocity.z,"
            "field.linear_acceleration.z",
            ["field.angular_velocity.x", "field.angular_velocity.z"],
        ),
        (  # Xsens MT Manager
            "PacketCounter,SampleTimeFine,Acc_X,Gyr_X,Gyr_Y,Gyr_Z,Mag_X",
            ["Gyr_X", "Gyr_Y", "Gyr_Z"],
        ),
        ("time,gx,gy,gz,temp_gyro", ["gx", "gy", "gz"]),
        (  # a STIM300's datagram as logged: not its counter, status, latency or CRC
            "counter,gyro_x,gyro_y,gyro_z,status,latency,crc",
            ["gyro_x", "gyro_y", "gyro_z"],
        ),
        ("Time (s),X,Y,Z,Temperature", ["X", "Y", "Z"]),  # times beside them: a record
        (  # Sensor Logger (a phone app): ns since 1970, then a second clock, not a rate
            "time,seconds_elapsed,z,y,x",
            ["z", "y", "x"],
        ),
        (  # an evaluation board's export: the samples' number is no rate either
            "Sample,Time (ms),X_GYRO (deg/s),Y_GYRO (deg/s),Z_GYRO (deg/s),TEMP (C)",
            ["X_GYRO (deg/s)", "Y_GYRO (deg/s)", "Z_GYRO (deg/s)"],
        ),
        ("hello,world", []),  # names of no record: nothing offered
    ],
)
def test_the_columns_offered_as_the_gyros_axis(header, offered):
    from app.core.column_roles import rate_column_choices
    from app.core.record_columns import ColumnChoiceNeeded

    assert rate_column_choices(header.split(",")) == offered
    with pytest.raises(ColumnChoiceNeeded) as raised:
        header_layout(header.split(","), guess=False)
    assert raised.value.choices == offered and raised.value.key == "allan.no_value_column"
    for column in offered:  # each offered is a column the reader takes
        assert header_layout(header.split(","), column).value_name == column


@pytest.mark.parametrize(
    "header",
    [
        "#position_1,position_2,position_3,position_4",
        "# sample, P1, P2, P3, P4",
        "#位置1,位置2,位置3,位置4",
    ],
)
def test_the_handouts_header_commented_out_heads_a_table_not_a_record(header):
    """A table whose header was commented out ("#position_1,…") names positions, not an
    IMU's axes: read as the handout's table (it was a record whose columns were offered as
    axes on the lab page, and refused by ``gyrolab solve``)."""
    from app.core.readings import parse_readings_csv
    from app.core.record_kinds import written_as_a_record
    from tests.factories import DATA

    rows = (DATA / "handout_horizontal.csv").read_text().splitlines()[1:]
    if "sample" not in header:
        rows = [row.split(",", 1)[1] for row in rows]
    text = "\n".join([header, *rows]) + "\n"
    assert not written_as_a_record(text)
    readings = parse_readings_csv(text, part="heading")
    assert [len(p) for p in readings.positions] == [10, 10, 10, 10]
    assert written_as_a_record("#timestamp [ns],w_x [rad s^-1]\n1403636579758555392,0.001\n")


def phyphox_text(separator: str, decimal: str) -> str:
    """A record as phyphox (the phone app labs use) exports its gyroscope: each header name
    quoted whatever the separator, numbers to ten significant digits in scientific form,
    rad/s, and no newline after the last line; here the independent white noise."""
    rates = np.radians(white_rates())
    names = ["Time (s)", "Gyroscope x (rad/s)", "Gyroscope y (rad/s)", "Gyroscope z (rad/s)"]
    lines = [separator.join(f'"{name}"' for name in [*names, "Absolute (rad/s)"])]
    for k, row in enumerate(rates):
        values = [*row, np.linalg.norm(row)]
        cells = [f"{k / RATE_HZ:.9E}", *(f"{value:.9E}" for value in values)]
        lines.append(separator.join(cell.replace(".", decimal) for cell in cells))
    return "\n".join(lines)


@pytest.mark.parametrize(
    ("separator", "decimal"),
    [(",", "."), ("\t", "."), (";", "."), ("\t", ","), (";", ",")],
    ids=["comma", "tab", "semicolon", "tab, decimal comma", "semicolon, decimal comma"],
)
def test_each_of_phyphoxs_csv_exports_keeps_its_times_and_offers_only_the_axes(separator, decimal):
    """phyphox quotes its header's names with every separator: with tabs or semicolons the
    quotes were kept, so "Time (s)" was no time column -- the times were lost and offered as
    a gyro axis -- and no axis could be chosen by its name; its "Absolute", the rate
    vector's length, is no axis either."""
    text = phyphox_text(separator, decimal)
    with pytest.raises(UserError) as asked:
        read(text)
    assert asked.value.choices == [
        "Gyroscope x (rad/s)",
        "Gyroscope y (rad/s)",
        "Gyroscope z (rad/s)",
    ]
    record = read(text, column="Gyroscope z")
    assert record.unit == "rad/s"
    assert record.times_s[:3] == pytest.approx([0.0, 0.01, 0.02], abs=1e-12)
    assert record.values == pytest.approx(np.radians(white_rates()[:, 2]), rel=1e-9)
    result = analyse_record(record, None)
    assert result.rate_hz == pytest.approx(RATE_HZ, rel=1e-9)
    assert result.arw_deg_rt_h == pytest.approx(ARW_DEG_RT_H, rel=0.05)


@pytest.mark.parametrize(
    ("header", "seconds_per_unit"),
    [
        ("Elapsed Time (s),Rate (deg/h)", 1.0),
        ("seconds_elapsed,rate_deg_h", 1.0),
        ("Time since start (ms),Rate (deg/h)", 1e-3),
        ("elapsed_s,value", 1.0),
        ("Zeit (s),Drehrate (°/h)", 1.0),
        ("历时(s),角速度(°/h)", 1.0),
        ("Rate (deg/h),Elapsed (us)", 1e-6),
    ],
)
def test_a_time_column_named_otherwise_keeps_the_records_times(header, seconds_per_unit):
    """A time column whose name is not one of the usual ones ("time", "t", "timestamp" …)
    but says times by its unit or its words: the times were dropped without a word, and
    with them the record's rate, its gaps and its warm-up check."""
    rates = [10.0 + 0.01 * (k % 7) for k in range(60)]
    times = [5 * k for k in range(60)]  # in the header's unit
    rate_first = header.startswith("Rate")
    text = (
        header
        + "\n"
        + "".join(
            f"{r},{t}\n" if rate_first else f"{t},{r}\n" for t, r in zip(times, rates, strict=True)
        )
    )
    record = read(text)
    assert record.values.tolist() == rates
    assert record.times_s == pytest.approx([seconds_per_unit * t for t in times], rel=1e-12)
    assert analyse_record(record, None).rate_hz == pytest.approx(1 / (5 * seconds_per_unit))


def test_a_column_chosen_that_is_the_times_is_read_without_times():
    record = read("Elapsed (s),Rate (deg/h)\n0,10\n1,11\n2,12\n", column="1")
    assert record.values.tolist() == [0.0, 1.0, 2.0] and record.times_s is None


@pytest.mark.parametrize(
    ("header", "rates_at"),
    [("time,x", 1), ("Time (s),gyro output", 1), ("z,time", 0), ("t,Time (s),x", 2)],
)
def test_the_one_column_beside_the_times_is_the_rates(header, rates_at):
    """A record of times and one column named otherwise ("time, x") is that column's
    record: it was refused as having no 'value' column, and "z, time" was read as times
    in "z" and rates in "time"."""
    rates = white_rates(seed=11, axes=1)[:, 0]
    width = len(header.split(","))
    rows = []
    for k, rate in enumerate(rates):
        cells = [f"{k / RATE_HZ:.2f}"] * width
        cells[rates_at] = repr(float(rate))
        rows.append(",".join(cells))
    record = read(header + "\n" + "\n".join(rows) + "\n")
    assert record.values.tolist() == rates.tolist()
    assert record.times_s == pytest.approx(np.arange(rates.size) / RATE_HZ)
    result = analyse_record(record, None)  # no unit named: the readings are in °/h
    assert result.arw_deg_rt_h == pytest.approx(ARW_DEG_RT_H / 3600, rel=0.05)


@pytest.mark.parametrize(
    "header",
    [
        "time,Time (s),sample",  # a second clock and a reading's number
        "time,Elapsed (s)",
        "Time (s),温度 (°C)",  # a logger of the case temperature alone
        "温度 (°C),t,序号,Temp",
        "t,Absolute",  # phyphox's |ω|: no axis
        "time,position",  # a long table's keys without its readings
    ],
)
def test_no_clock_count_or_temperature_is_taken_for_the_rates(header):
    """Beside the times, columns that are a second clock, a reading's number or a
    temperature are no rates: the lab page's preview read "Time (s)" or "sample" as the
    gyro's rates, and ``gyrolab allan`` gave the Allan deviation of a clock."""
    from app.lab.file_pages import parse_csv_upload
    from app.lab.schemas import CsvUpload

    width = len(header.split(","))
    text = header + "\n" + "".join(",".join([f"{k * 0.1:.1f}"] * width) + "\n" for k in range(40))
    for guess in (True, False):  # the command line guesses, the lab page does not
        with pytest.raises(UserError) as error:
            read_static_record(text_lines(text.encode()), guess=guess)
        assert error.value.key == "allan.no_rate_column"
    with pytest.raises(UserError) as error:
        parse_csv_upload(CsvUpload(text=text, unit="deg/h", part="heading"), suggest=True)
    assert error.value.key == "allan.no_rate_column"
    assert header.split(",")[0] in error.value.params["columns"]


def test_unknown_names_beside_the_times_are_asked_not_guessed():
    """ "time, a, b": which of a and b is the rates cannot be told; the command line read a
    as the rates and b as the case temperature, as if there were no header."""
    from app.core.record_columns import ColumnChoiceNeeded

    with pytest.raises(ColumnChoiceNeeded) as raised:
        header_layout(["time", "a", "b"])
    assert raised.value.choices == ["a", "b"] and raised.value.key == "allan.no_value_column"
    layout = header_layout(["time", "a", "b"], "b")
    assert (layout.value, layout.time, layout.temperature) == (2, 0, None)
    bare = header_layout(["a", "b", "c"])  # no name known: as without a header
    assert (bare.value, bare.time, bare.temperature) == (1, 0, 2)


def test_a_record_of_several_positions_is_said_to_be_so():
    """The long layout's table (``time_s, position, value``) given for an Allan analysis:
    "needs one position, not 4" -- it was "line 2 is not a reading", a line that is one."""
    text = "time_s,position,value\n" + "".join(
        f"{k * 0.1:.1f},{1 + k // 10},{10 + 0.01 * (k % 3)}\n" for k in range(40)
    )
    with pytest.raises(UserError) as error:
        read(text)
    assert error.value.key == "allan.one_position" and error.value.params == {"count": 4}
