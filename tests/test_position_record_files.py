"""One position's record as a real gyro's logger writes it -- one reading per line, or
its clock and the reading, a header with units -- uploaded on the lab page's CSV method
for the position the student chooses: previewed with the first position not yet
recorded suggested, saved with its times, and refused with a reason where it is not one."""

from __future__ import annotations

import datetime as dt

import numpy as np
import pytest
from sqlmodel import select

from app.db import read_session
from app.lab.samples import unpack
from app.lab.store import load_samples
from app.models import SampleChunk, Take
from tests.factories import HEADING, login, new_session, post_json

# the file's reading is the new part; the saving is the CSV method's, tested on both databases
pytestmark = pytest.mark.one_backend


@pytest.fixture
def lab(client, student):
    assert login(client, "student1").status_code == 303
    session_id = new_session(client)
    page = f"/lab/sessions/{session_id}"

    def send(path: str, text: str, **extra):
        body = {"part": "heading", "unit": "deg/h", "text": text, **extra}
        return post_json(client, page + path, body, page)

    return send


def logger_file(values, start=dt.datetime(2026, 11, 28, 14, 0, 0), step_s=0.5) -> str:
    stamps = (start + dt.timedelta(seconds=k * step_s) for k in range(len(values)))
    return "Time,Rate (deg/h)\n" + "".join(
        f"{t:%Y-%m-%d %H:%M:%S.%f},{v}\n" for t, v in zip(stamps, values, strict=True)
    )


def test_a_loggers_file_for_one_position_previewed_then_saved_where_chosen(lab):
    values = HEADING[2]  # the handout's position 2
    preview = lab("/csv/preview", logger_file(values))
    assert preview.status_code == 200, preview.text
    body = preview.json()
    assert body["layout"] == "record" and body["position_count"] == 4
    [row] = body["positions"]
    assert row["position"] == 1 and row["n"] == len(values)  # the first not yet recorded
    assert row["mean_deg_h"] == pytest.approx(np.mean(values))
    assert "one position's record" in body["notes"][0]
    chosen = lab("/csv/preview", logger_file(values), position=2).json()["positions"][0]
    assert chosen["position"] == 2 and abs(chosen["angle_deg"] - row["angle_deg"]) == 90.0
    refused = lab("/csv", logger_file(values))
    assert refused.status_code == 400 and "choose the position" in refused.json()["detail"]
    saved = lab("/csv", logger_file(values), position=2)
    assert saved.status_code == 200 and saved.json()["saved"] == [2]
    with read_session() as db:
        [take] = db.exec(select(Take)).all()
        chunk = db.exec(select(SampleChunk)).first()
    assert (take.part, take.position, take.n_samples) == ("heading", 2, len(values))
    assert unpack(chunk.times)[:3].tolist() == [0.0, 0.5, 1.0]  # the logger's clock
    # the next file suggests the first position still empty
    assert lab("/csv/preview", logger_file(values)).json()["positions"][0]["position"] == 1


def test_a_loggers_file_cut_off_mid_line_is_saved_without_its_last_line_and_says_so(lab):
    """The logger was unplugged while it wrote: its last line is half a reading.  The
    preview reads the rest and says which line was left out; the save stores the same."""
    values = HEADING[2]
    cut = "2026-11-28 14:00:05.000,10.74"[:22]  # the clock's cell, cut before its end
    text = logger_file(values) + cut
    preview = lab("/csv/preview", text, position=2).json()
    assert preview["positions"][0]["n"] == len(values)
    assert any(
        f"Line {len(values) + 2} ('{cut}'), the file's last, is not a reading" in note
        for note in preview["notes"]
    ), preview["notes"]
    saved = lab("/csv", text, position=2)
    assert saved.status_code == 200 and saved.json()["saved"] == [2]
    with read_session() as db:
        [take] = db.exec(select(Take)).all()
    assert take.n_samples == len(values)


def test_a_loggers_lost_readings_are_left_out_of_the_position_and_said(lab):
    """LabVIEW writes NaN for a reading it lost, an old Windows logger 1.#QNAN: one such
    line had refused the whole file.  The preview and the save leave them out, and say so."""
    values = [str(v) for v in [*HEADING[2], *HEADING[2]]]  # 20: 18 left, n ≥ 10 still
    values[3], values[7] = "NaN", "1.#QNAN"
    text = logger_file(values)
    preview = lab("/csv/preview", text, position=2).json()
    assert preview["positions"][0]["n"] == len(values) - 2
    assert any("Lost readings" in note and "reading 4" in note for note in preview["notes"])
    saved = lab("/csv", text, position=2)
    assert saved.status_code == 200 and saved.json()["saved"] == [2]
    with read_session() as db:
        [take] = db.exec(select(Take)).all()
    assert take.n_samples == len(values) - 2


def test_a_loggers_lines_about_the_record_are_passed_over_and_said_in_the_preview(lab):
    text = "Device: FOG-50\nOperator: Li Si\n" + logger_file(HEADING[2])
    preview = lab("/csv/preview", text, position=2).json()
    assert preview["positions"][0]["n"] == len(HEADING[2])
    assert any("Lines 1–2 above the readings ('Device: FOG-50'" in n for n in preview["notes"])


def test_a_labview_file_for_one_position_is_previewed_and_saved_as_a_record(lab):
    """LabVIEW's .lvm (its headers look like a table of two columns to the table reader,
    whose "second table" it was): read as one position's record, said in the preview."""
    from tests.test_labview_lvm import lvm

    values = np.array(HEADING[3] * 6)
    text = lvm(values)
    preview = lab("/csv/preview", text, position=3).json()
    assert preview["positions"][0]["n"] == values.size
    assert (
        "Read as a LabVIEW measurement file (.lvm): its headers, lines 1–21, were passed over."
        in preview["notes"]
    )
    saved = lab("/csv", text, position=3)
    assert saved.status_code == 200 and saved.json()["saved"] == [3]
    with read_session() as db:
        [take] = db.exec(select(Take)).all()
        values_stored, times = load_samples(db, take)
    assert values_stored == pytest.approx(values) and times[1] == pytest.approx(0.1)


def test_one_reading_per_line_is_one_positions_record(lab):
    text = "".join(f"{v}\n" for v in HEADING[3])
    saved = lab("/csv", text, position=3)
    assert saved.status_code == 200 and saved.json()["saved"] == [3]


@pytest.mark.parametrize(
    ("text", "unit", "message"),
    [
        ("Time (s),Rate (deg/s)\n0,0.003\n0.5,0.004\n", "deg/h", "in °/s, but °/h is chosen"),
        ("time_s,dtheta [rad]\n0,1e-7\n0.1,2e-7\n", "deg/h", "gives angles in rad, not rates"),
        ("time_s,value\n0,10.7\n0.5,abc\n", "deg/h", "Line 3 of the record is not a reading"),
        ("hello,world\n1,2\n", "deg/h", "reads 'hello | world'"),  # names of no record
        ("10.7,10.1\n10.6,10.2\n10.8,10.0\n", "deg/h", "reads '10.7 | 10.1'"),  # not times
    ],
)
def test_what_is_no_record_or_a_bad_one_says_why(lab, text, unit, message):
    for path in ("/csv/preview", "/csv"):
        response = lab(path, text, unit=unit, position=1)
        assert response.status_code == 400, (path, response.text)
        assert message in response.json()["detail"]
    with read_session() as db:
        assert db.exec(select(Take)).all() == []


def test_a_header_in_the_chosen_unit_is_read(lab):
    text = "Time (s),Rate (deg/s)\n" + "".join(
        f"{k * 0.5},{v / 3600.0!r}\n" for k, v in enumerate(HEADING[1])
    )
    preview = lab("/csv/preview", text, unit="deg/s", position=1).json()
    assert preview["positions"][0]["mean_deg_h"] == pytest.approx(np.mean(HEADING[1]))


def imu_file(axis_z: list[float]) -> str:
    """An IMU's record as EuRoC and Kalibr write it: ns since 1970 behind '#', three gyro
    axes in rad/s and three accelerometer axes; the gyro's sensitive axis is z (the
    x and y axes hold other numbers, so that reading the wrong axis shows)."""
    deg_h = np.pi / 180.0 / 3600.0
    lines = [
        "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
        "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]"
    ]
    for k, value in enumerate(axis_z):
        stamp = 1_403_636_579_758_555_392 + k * 500_000_000
        lines.append(f"{stamp},{1e-3 + k * 1e-6!r},{-2e-3!r},{value * deg_h!r},0.01,-0.02,9.81")
    return "\n".join(lines) + "\n"


def test_an_imus_record_is_read_from_the_column_the_student_chooses(lab):
    values = HEADING[4]
    text = imu_file(values)
    preview = lab("/csv/preview", text, unit="rad/s")
    assert preview.status_code == 200, preview.text
    body = preview.json()
    offered = [c["value"] for c in body["columns"]]
    # the gyro's three axes, not the time or the accelerometer's
    assert offered == ["w_RS_S_x [rad s^-1]", "w_RS_S_y [rad s^-1]", "w_RS_S_z [rad s^-1]"]
    assert body["column"] == offered[0] and "3 columns that may be the gyro's rate" in str(
        body["notes"]
    )
    assert body["positions"][0]["mean_deg_h"] != pytest.approx(np.mean(values), rel=0.01)
    chosen = lab("/csv/preview", text, unit="rad/s", column=offered[2]).json()
    assert chosen["column"] == offered[2]
    assert chosen["positions"][0]["mean_deg_h"] == pytest.approx(np.mean(values))
    # saved only with a column said: the API and a script never guess an axis
    refused = lab("/csv", text, unit="rad/s", position=4)
    assert refused.status_code == 400
    assert "say which column is the gyro's axis" in refused.json()["detail"]
    unknown = lab("/csv", text, unit="rad/s", position=4, column="w_RS_S_q")
    assert unknown.status_code == 400 and "w_RS_S_z [rad s^-1]" in unknown.json()["detail"]
    with read_session() as db:
        assert db.exec(select(Take)).all() == []
    saved = lab("/csv", text, unit="rad/s", position=4, column="w_RS_S_z")  # its name is enough
    assert saved.status_code == 200 and saved.json()["saved"] == [4]
    with read_session() as db:
        chunk = db.exec(select(SampleChunk)).first()
    assert unpack(chunk.times)[:3].tolist() == [0.0, 0.5, 1.0]
    assert unpack(chunk.values) == pytest.approx(values)  # stored in °/h


def test_a_table_of_bare_columns_stays_a_table_of_positions(lab):
    """Four columns of numbers without a header are the handout's table of positions, as
    before; nothing is offered as an axis."""
    text = "".join(f"{a},{b},{c},{d}\n" for a, b, c, d in zip(*HEADING.values(), strict=True))
    body = lab("/csv/preview", text).json()
    assert body["layout"] != "record" and len(body["positions"]) == 4
    assert body["columns"] == [] and body["column"] is None


def test_a_long_file_saves_each_position_as_the_number_it_gives(lab):
    """ "position, rate" with position 3 alone is position 3 -- not position 1 -- and a
    file by the dial's angles fills the positions at those angles."""
    text = "position,rate\n" + "".join(f"3,{v}\n" for v in HEADING[3])
    [row] = lab("/csv/preview", text).json()["positions"]
    assert row["position"] == 3 and row["n"] == len(HEADING[3])
    assert lab("/csv", text).json()["saved"] == [3]
    # the handout's session turns counter-clockwise: position 2 is at -90° (270°)
    by_angle = "转台角度,读数\n" + "".join(
        f"{angle},{v}\n" for angle, k in ((0, 1), (270, 2)) for v in HEADING[k]
    )
    rows = lab("/csv/preview", by_angle).json()["positions"]
    assert [(r["position"], r["angle_deg"]) for r in rows] == [(1, 0.0), (2, 270.0)]
    assert lab("/csv", by_angle).json()["saved"] == [1, 2]
    with read_session() as db:
        takes = db.exec(select(Take).where(Take.superseded_at == None)).all()  # noqa: E711
    assert sorted((t.position, t.n_samples) for t in takes) == [
        (k, len(HEADING[k])) for k in (1, 2, 3)
    ]


def test_a_template_not_filled_in_is_refused_in_words(lab, client):
    """The handout's header alone, saved before the readings were typed: was a 500."""
    for path in ("/csv/preview", "/csv"):
        refused = lab(path, "position_1,position_2,position_3,position_4\n")
        assert (
            refused.status_code == 400 and refused.json()["detail"] == "The file has no readings."
        )
    client.cookies.set("gyrolab_lang", "zh-CN")
    refused = lab("/csv/preview", "位置1,位置2,位置3,位置4\n")
    assert refused.status_code == 400 and "没有读数" in refused.json()["detail"]


def axes_file(header: str, axis_z, rate_hz: float = 10.0, unit_scale: float = 1.0) -> str:
    """An IMU's export with its times in the first column and no '#' before its header:
    x, y and z with the z axis ``axis_z`` (°/h) written in the header's unit."""
    lines = [header]
    for k, value in enumerate(axis_z):
        z = float(value) * unit_scale
        lines.append(f"{k / rate_hz:.2f},{0.3 * unit_scale},{-0.2 * unit_scale},{z!r}")
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize(
    ("header", "unit", "scale", "z"),
    [
        ("time,gx,gy,gz", "deg/h", 1.0, "gz"),
        ("Time (s),Gyro X (deg/s),Gyro Y (deg/s),Gyro Z (deg/s)", "deg/s", 1 / 3600, "Gyro Z"),
        (
            '"Time (s)";"Gyroscope x (rad/s)";"Gyroscope y (rad/s)";"Gyroscope z (rad/s)"',
            "rad/s",
            np.pi / 180 / 3600,
            "Gyroscope z",
        ),
    ],
    ids=["bare names", "units in the names", "phyphox, semicolons"],
)
def test_an_imus_export_with_a_time_column_is_one_record_not_a_table(lab, header, unit, scale, z):
    """Its header was taken for a line about a table and its columns for positions -- the
    times position 1 -- and it was saved so. Now it is one position's record: its axes
    offered, the times its times."""
    values = HEADING[3]
    text = axes_file(header, values, unit_scale=scale)
    if ";" in header:
        text = text.replace(",", ";")
    preview = lab("/csv/preview", text, unit=unit)
    assert preview.status_code == 200, preview.text
    body = preview.json()
    assert body["layout"] == "record" and len(body["positions"]) == 1
    assert [c["value"] for c in body["columns"]][2].startswith(z)
    saved = lab("/csv", text, unit=unit, position=3, column=z)
    assert saved.status_code == 200 and saved.json()["saved"] == [3], saved.text
    with read_session() as db:
        chunk = db.exec(select(SampleChunk)).one()
    assert unpack(chunk.times)[:3].tolist() == [0.0, 0.1, 0.2]
    assert unpack(chunk.values) == pytest.approx(values)  # stored in °/h
