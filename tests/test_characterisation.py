"""A real gyro's Allan characterisation, uploaded by the teacher for an assignment: fitted,
stored, used for the σ of real-gyro readings, validated, and only the teacher's."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from app.core.gyro_stream import GyroStream
from app.core.noise_model import GyroNoise, Window, four_position_sigma
from app.core.presets import PRESETS
from app.core.solve import solve_heading
from app.db import read_session, write_session
from app.models import Assignment, Role
from tests.factories import HEADING, browser, make_course, make_user, save_manual, start


@pytest.fixture
def world(app, teacher):
    """teacher1's course with one student and an assignment for a real bench."""
    student = make_user("s1", Role.student, name="学生1")
    course_id = make_course(teacher, "Bench lab", (student,))
    with write_session() as db:
        assignment = Assignment(
            course_id=course_id, title="Bench", latitude_deg=39.93, earth_rate_deg_h=15.04
        )
        db.add(assignment)
        db.flush()
        return {"course": course_id, "assignment": assignment.id, "app": app}


def static_record(hours: float = 2.0, seed: int = 1) -> tuple[str, object]:
    gyro = replace(PRESETS["tactical-fog"], turn_on_bias_sigma_deg_h=0.0).without("warmup")
    values = GyroStream(gyro, seed).read(np.full(int(hours * 3600 * gyro.sample_rate_hz), 11.5))
    return "rate_deg_h\n" + "\n".join(f"{v:.6f}" for v in values) + "\n", gyro


def upload(client, world, text: str | bytes, rate: str = "10", **extra):
    page = f"/courses/{world['course']}/assignments/{world['assignment']}"
    token = client.get(page).text.split('name="csrf_token" value="')[1].split('"')[0]
    content = text.encode() if isinstance(text, str) else text
    return client.post(
        f"{page}/characterisation",
        data={"csrf_token": token, "rate_hz": rate, **extra},
        files={"record": ("bench.csv", content, "text/csv")},
    )


def shown(client, reply) -> str:
    """The page the teacher sees after an upload: the dashboard it redirects to once
    stored, or (refused) the dashboard again with the refusal beside its field."""
    if reply.status_code == 303:
        return client.get(reply.headers["location"]).text
    assert reply.status_code in (400, 503), reply.status_code
    return reply.text


def stored(world) -> dict | None:
    with read_session() as db:
        value = db.get(Assignment, world["assignment"]).gyro_characterisation
    return None if value is None else json.loads(value)


def test_teacher_characterises_the_bench_gyro_and_real_readings_use_it(world):
    teacher = browser(world, "teacher1")
    text, gyro = static_record()
    reply = upload(teacher, world, text, rate="１０")  # typed with a Chinese input method
    assert reply.status_code == 303
    page = shown(teacher, reply)
    assert "Characterisation stored" in page
    summary = stored(world)
    assert summary["arw_deg_rt_h"] == pytest.approx(gyro.arw_deg_rt_h, rel=0.05)
    low, high = summary["terms"]["arw"]["interval"]
    assert low < summary["arw_deg_rt_h"] < high
    assert "angle random walk N" in page and "not resolved" in page  # K: a bound, no value
    assert summary["rate_hz"] == 10.0 and summary["samples"] == 72000
    assert "68 % interval" in page
    # the settings form does not touch it
    dashboard = f"/courses/{world['course']}/assignments/{world['assignment']}"
    token = teacher.get(dashboard).text.split('name="csrf_token" value="')[1].split('"')[0]
    form = {"csrf_token": token, "title": "Find north", "latitude_deg": "39.93",
            "earth_rate_deg_h": "15.04", "simulator_preset": "teaching-fog",
            "min_readings": "10", "methods": ["manual", "csv", "simulator"]}  # fmt: skip
    assert teacher.post(f"{dashboard}/settings", data=form).status_code == 303
    assert stored(world) == summary
    # a student's typed readings now get the characterised gyro's σ
    student = browser(world, "s1")
    session_id = start(student, world)
    assert save_manual(student, session_id, "heading", HEADING).status_code == 200
    result = student.get(f"/lab/sessions/{session_id}/results.json").json()["heading"]
    assert result["uncertainty_model"] == "allan"
    noise = GyroNoise(
        arw_deg_rt_h=summary["arw_deg_rt_h"],
        bias_instability_deg_h=summary["bias_instability_deg_h"],
        rrw_deg_h_rt_h=summary["rrw_deg_h_rt_h"],
        angle_lsb_deg=summary["quantization_deg"] * 12**0.5,
        flicker_band_s=tuple(summary["flicker_band_s"]),
    )
    positions = [HEADING[k] for k in sorted(HEADING)]
    windows = [Window(0.0, len(p) / 10.0) for p in positions]
    expected = solve_heading(
        positions,
        [0.0, -90.0, -180.0, -270.0],
        position_cov=noise.mean_covariance(windows, continuous=False),
        expected_amplitude_deg_h=15.04 * math.cos(math.radians(39.93)),  # the station's H
    )
    assert result["azimuth_sigma_deg"] == pytest.approx(expected.azimuth_sigma_deg, rel=1e-9)
    # removed: back to white noise
    assert upload(teacher, world, b"", remove="1").status_code == 303
    assert stored(world) is None
    result = student.get(f"/lab/sessions/{session_id}/results.json").json()["heading"]
    assert result["uncertainty_model"] == "white"


def damaged_gzip() -> bytes:
    """A gzip-compressed record with a byte of its compressed data flipped (zlib's
    "invalid distance too far back", or another such error, where it is read)."""
    import gzip

    rng = np.random.default_rng(8)
    packed = bytearray(
        gzip.compress("".join(f"{v!r}\n" for v in rng.normal(size=7000).tolist()).encode())
    )
    packed[20] ^= 0xFF  # early in the first block (a byte in the middle: the CRC's error)
    return bytes(packed)


@pytest.mark.one_backend  # input refused before any write
@pytest.mark.parametrize(
    ("content", "rate", "message"),
    [
        (b"", "10", "Choose the record"),
        ("1\n2\n3\n", "10", "at least 600 s"),
        ("x\n" + "1.0\n" * 7000, "abc", "sample rate must be"),
        ("x\n" + "1.0\n" * 7000, "0", "sample rate must be"),
        ("x\n" + "1.0\n" * 7000, "1e9", "sample rate must be"),
        ("x\n" + "1.0\n" * 7000 + "oops\n", "10", "Line 7002 of the record is not a reading"),
        ("position_1,position_2\n1,2\n", "10", "one static record"),
        ("x\n" + "1.0\n" * 7000, "10", "never change"),
        (b"\x00\x01\x81\x00", "10", "not text (UTF-8, UTF-16, GB18030 or Windows-1252)"),
        # a gzip whose compressed data is damaged: zlib.error, a 500
        (damaged_gzip(), "10", "The compressed file is damaged or incomplete."),
        (damaged_gzip()[:200], "10", "The compressed file is damaged or incomplete."),
        # rates no gyro gives: the fit's squares overflowed (a 500)
        (
            "".join(f"{(-1) ** k * 3e300 * (1 + k % 7)!r}\n" for k in range(7000)),
            "10",
            "out of range for an angular rate",
        ),
    ],  # fmt: skip
)
def test_bad_records_are_explained_and_nothing_is_stored(world, content, rate, message):
    teacher = browser(world, "teacher1")
    reply = upload(teacher, world, content, rate)
    assert reply.status_code == 400
    assert message in reply.text  # beside its field, the section's form as typed
    assert stored(world) is None


def test_a_bench_record_cut_off_at_its_end_is_analysed_and_the_page_says_so(world):
    """The logger was unplugged mid-line: the record is analysed without its last line,
    and the teacher's page names the line that was left out."""
    teacher = browser(world, "teacher1")
    text, _ = static_record(hours=0.5)
    rates = text.splitlines()[1:]
    timed = "time_s,rate_deg_h\n" + "".join(f"{k / 10:.1f},{v}\n" for k, v in enumerate(rates))
    page = shown(teacher, upload(teacher, world, timed + f"{len(rates) / 10:.1f},"))
    assert "Characterisation stored" in page
    assert stored(world)["samples"] == len(rates)
    quoted = f"{len(rates) / 10:.1f},"
    assert (
        f"Line {len(rates) + 2} (&#39;{quoted}&#39;), the file&#39;s last, is not a reading" in page
    )


def test_only_the_courses_teacher_may_characterise(world):
    make_user("teacher2", Role.teacher)
    other = browser(world, "teacher2")
    page = f"/courses/{world['course']}/assignments/{world['assignment']}"
    token = other.get("/").text.split('name="csrf_token" value="')[1].split('"')[0]
    reply = other.post(
        f"{page}/characterisation",
        data={"csrf_token": token, "rate_hz": "10"},
        files={"record": ("a.csv", b"1\n" * 10, "text/csv")},
    )
    assert reply.status_code == 404 and stored(world) is None


def test_one_axis_of_an_imu_record_compressed_with_its_times(world):
    """Issue 30: a bench record as instruments write it -- three axes, a time column, no
    rate given, gzip-compressed -- characterised from the column the teacher names."""
    import gzip

    teacher = browser(world, "teacher1")
    text, gyro = static_record(hours=0.5)
    values = text.splitlines()[1:]
    lines = ["t,gx,gy,gz"] + [f"{k / 10:.1f},0.0,{v},1.0" for k, v in enumerate(values)]
    packed = gzip.compress("\n".join(lines).encode())
    reply = upload(teacher, world, packed, rate="", column="gy")
    assert reply.status_code == 303
    summary = stored(world)
    assert summary is not None and summary["rate_hz"] == pytest.approx(10.0)
    assert summary["arw_deg_rt_h"] == pytest.approx(gyro.arw_deg_rt_h, rel=0.1)
    reply = upload(teacher, world, packed, rate="", column="gq")
    assert "has no column" in shown(teacher, reply)
    # without a column: the gyro's axes are named, and what was typed comes back
    reply = upload(teacher, world, packed, rate="10", unit="deg/h")
    page = shown(teacher, reply)
    assert "the columns that may hold the rates: gx, gy, gz" in page
    beside = page.split('id="field-characterisation-column"')[1].split("</label>")[0]
    assert 'class="field-error" id="error-characterisation-column"' in beside  # beside it
    assert "gx, gy, gz" in beside
    assert 'name="rate_hz" inputmode="decimal" placeholder="10" value="10"' in page
    assert '<option value="deg/h" selected>' in page
    reply = upload(teacher, world, packed, rate="", column='gq"><b>x')
    page = shown(teacher, reply)
    assert 'value="gq&#34;&gt;&lt;b&gt;x"' in page and "<b>x" not in page  # escaped


def test_one_bench_record_is_analysed_at_a_time(world):
    """Issue 31 (bounded work): a second Allan analysis while one runs in this process is
    refused with a message (10⁷ readings take ≈ 13 s and 0.6 GB); nothing is stored."""
    from app.web.work_slots import pool

    teacher = browser(world, "teacher1")
    text, _gyro = static_record(hours=0.3)
    pool("analysis").take(99_999)  # another teacher's analysis under way
    try:
        reply = upload(teacher, world, text)
        assert "analysing another record" in shown(teacher, reply)
        assert stored(world) is None
    finally:
        pool("analysis").give_back(99_999)
    upload(teacher, world, text)
    assert stored(world) is not None


@pytest.mark.one_backend  # the record's reading does not depend on the database
def test_a_loggers_record_with_its_clock_and_no_rate(world):
    """A logger's record -- its clock for the time, spaces between the columns, running
    past midnight -- characterised without a rate given: the rate comes from the clock."""
    import datetime as dt

    teacher = browser(world, "teacher1")
    text, gyro = static_record(hours=0.5)
    start = dt.datetime(2026, 11, 28, 23, 50)
    lines = [
        f"{start + dt.timedelta(seconds=k / 10):%Y-%m-%d %H:%M:%S.%f}  {value}"
        for k, value in enumerate(text.splitlines()[1:])
    ]
    reply = upload(teacher, world, "\n".join(lines) + "\n", rate="")
    assert reply.status_code == 303
    summary = stored(world)
    assert summary is not None and summary["rate_hz"] == pytest.approx(10.0)
    assert summary["arw_deg_rt_h"] == pytest.approx(gyro.arw_deg_rt_h, rel=0.1)


@pytest.mark.one_backend  # refused before any write
def test_a_record_that_needs_its_column_chosen_offers_the_columns(world):
    """A FOG logger's bare four columns: refused with the columns to choose from, which
    the column field then offers (a datalist); chosen, the first column is the times."""
    teacher = browser(world, "teacher1")
    rng = np.random.default_rng(8)
    text = "#2022-01-27 20:10:44\n" + "".join(
        f"{0.01 * k:.2f}, {rate:.5f}, {k % 97}, 35.5\n"
        for k, rate in enumerate(rng.normal(0.0, 0.05, 72_000))
    )
    reply = upload(teacher, world, text, rate="")
    assert reply.status_code == 400 and stored(world) is None
    page = reply.text
    assert 'list="characterisation-columns"' in page
    offered = page.split('<datalist id="characterisation-columns">')[1].split("</datalist>")[0]
    assert offered == "".join(f'<option value="{k}"></option>' for k in ("2", "3", "4", "1"))
    reply = upload(teacher, world, text, rate="", column="2", unit="deg/s")
    assert reply.status_code == 303
    assert stored(world)["rate_hz"] == pytest.approx(100.0)
    assert "its first column, which rises through the record" in shown(teacher, reply)


@pytest.mark.one_backend  # the record's reading does not depend on the database
def test_a_record_saved_as_unicode_text_is_read(world):
    """A spreadsheet's "Unicode text" (UTF-16 with its byte-order mark, tab-separated):
    refused as "not text" before."""
    teacher = browser(world, "teacher1")
    rates = np.random.default_rng(6).normal(10.0, 0.5, 7_200)
    text = "time\trate\r\n" + "".join(f"{0.1 * k:.1f}\t{r:.4f}\r\n" for k, r in enumerate(rates))
    reply = upload(teacher, world, text.encode("utf-16"), rate="")
    assert reply.status_code == 303, reply.text[-500:]
    assert stored(world)["rate_hz"] == pytest.approx(10.0)


@pytest.mark.one_backend  # the record's reading does not depend on the database
def test_a_record_saved_as_an_excel_workbook_is_read(world):
    """A bench record a teacher kept in Excel (.xlsx): its sheet of readings read as its
    CSV would be, the rate from its time column."""
    import io

    import xlsxwriter

    teacher = browser(world, "teacher1")
    rates = np.random.default_rng(7).normal(10.0, 0.5, 7_200)
    buffer = io.BytesIO()
    book = xlsxwriter.Workbook(buffer, {"in_memory": True})
    sheet = book.add_worksheet()
    sheet.write_row(0, 0, ["time_s", "rate (deg/h)"])
    for k, rate in enumerate(rates, start=1):
        sheet.write_row(k, 0, [0.1 * (k - 1), float(rate)])
    book.close()
    reply = upload(teacher, world, buffer.getvalue(), rate="")
    assert reply.status_code == 303, reply.text[-500:]
    summary = stored(world)
    assert summary["rate_hz"] == pytest.approx(10.0) and summary["samples"] == 7_200


def test_a_device_faster_than_the_characterisation_gets_the_sigma_of_its_own_span(world):
    """A teacher characterises the bench gyro from a 10 Hz logger; a group's bridge sends
    the same gyro at 1 kHz with its times.  Each position mean averages over its own span
    (5 s here), so its σ is 60·N/√5 (lab-reference §3), not that of 5000 readings taken
    as 500 s at the characterisation's rate (√100 = 10× too small).  Readings without
    times, or spread wider than their count allows, still count at the characterisation's
    rate.  An independent white-noise Monte
    Carlo at 1 kHz scatters as the σ says."""
    arw, rate, count = 0.01, 1000.0, 5000
    summary = {"arw_deg_rt_h": arw, "bias_instability_deg_h": 0.0, "rrw_deg_h_rt_h": 0.0,
               "quantization_deg": 0.0, "rate_hz": 10.0, "terms": {}}  # fmt: skip
    with write_session() as db:
        db.get(Assignment, world["assignment"]).gyro_characterisation = json.dumps(summary)
    student = browser(world, "s1")
    from tests.factories import API, token_for

    auth = token_for(student, "s1")
    h = 15.04 * math.cos(math.radians(39.93))
    angles = [0.0, -90.0, -180.0, -270.0]
    rng = np.random.default_rng(7)
    per_reading = 60.0 * arw * math.sqrt(rate)  # white noise of ARW N at 1 kHz (°/h)

    def readings(azimuth: float) -> list[np.ndarray]:
        return [h * np.cos(np.radians(azimuth + a)) + 0.3 + rng.normal(0, per_reading, count)
                for a in angles]  # fmt: skip

    def sigma_of(timed: bool) -> dict:
        body = {"assignment_id": world["assignment"]}
        session_id = student.post(f"{API}/sessions", json=body, headers=auth).json()["id"]
        for k, values in enumerate(readings(30.0), 1):
            upload = {"samples": values.tolist()}
            if timed:
                upload["times_s"] = (100.0 * k + np.arange(count) / rate).tolist()
            url = f"{API}/sessions/{session_id}/heading/positions/{k}"
            assert student.put(url, json=upload, headers=auth).status_code == 200
        result = student.get(f"{API}/sessions/{session_id}/results", headers=auth).json()
        assert result["heading"]["uncertainty_model"] == "allan"
        return result["heading"]

    # σ = 60·N/√T for each mean and σ_A = σ/(√2·H) (lab-reference §3), in °/h and degrees
    def mean_sigma(seconds: float) -> float:
        return 60.0 * arw / math.sqrt(seconds)

    def closed_form(seconds: float) -> float:
        return math.degrees(mean_sigma(seconds) / (math.sqrt(2.0) * h))

    timed = sigma_of(timed=True)
    assert timed["position_sigmas_deg_h"] == pytest.approx([mean_sigma(count / rate)] * 4)
    assert timed["azimuth_sigma_deg"] == pytest.approx(closed_form(count / rate), rel=0.02)
    # without times: 5000 readings at 10 Hz, 500 s -- and the readings' scatter, ten times
    # that, is then flagged (the closure far beyond its σ) and widens the result's σ
    untimed = sigma_of(timed=False)
    assert untimed["position_sigmas_deg_h"] == pytest.approx([mean_sigma(count / 10.0)] * 4)
    assert untimed["warm_up"]["flagged"]
    # the span: first to last time plus one step
    from types import SimpleNamespace

    from app.lab.results import recorded_seconds

    position = SimpleNamespace(times=np.arange(count) / rate, values=np.zeros(count))
    assert recorded_seconds(position, 10.0) == pytest.approx(5.0)
    assert recorded_seconds(SimpleNamespace(times=None, values=np.zeros(count)), 10.0) == 500.0
    # ten single samples logged 10 s apart from the 10 Hz gyro: each as noisy as one 0.1 s
    # sample, so the count's 1 s, not the 100 s span
    sparse = SimpleNamespace(times=10.0 * np.arange(10), values=np.zeros(10))
    assert recorded_seconds(sparse, 10.0) == 1.0
    # independent Monte Carlo: the RMS heading error against the σ for 5 s windows
    noise = GyroNoise(arw_deg_rt_h=arw, bias_instability_deg_h=0.0, rrw_deg_h_rt_h=0.0)
    cov = noise.mean_covariance([Window(0.0, count / rate)] * 4, continuous=False)
    errors = []
    for _run in range(300):
        azimuth = float(rng.uniform(0.0, 360.0))
        solved = solve_heading(readings(azimuth), angles, position_cov=cov,
                               true_azimuth_deg=azimuth)  # fmt: skip
        errors.append(solved.azimuth_error_deg)
    rms = math.sqrt(float(np.mean(np.square(errors))))
    assert rms == pytest.approx(closed_form(count / rate), rel=0.12)  # 300 runs: ±4 %


@pytest.mark.one_backend  # the record's analysis does not depend on the database
def test_a_bench_whose_floor_and_walk_no_term_carries_alone_keeps_their_noise(world):
    """A FOG whose curve levels off from a flicker floor and a random walk that neither
    alone carries (only N resolved): the stored noise model, which gives real readings their
    1σ, was N alone -- white noise, whose σ keeps falling with the dwell where the gyro's
    does not.  It now holds the fitted curve's floor and walk, as the dwell advice does."""
    from tests.noise_sources import static_record as independent_record

    rates = independent_record(2.5, 10.0, arw=0.005, flicker=0.02, rrw=0.05, seed=0)
    text = "time_s,value\n" + "".join(f"{k / 10:.1f},{r:.6f}\n" for k, r in enumerate(rates))
    teacher = browser(world, "teacher1")
    assert upload(teacher, world, text).status_code == 303
    summary = stored(world)
    assert not summary["terms"]["bias_instability"]["resolved"]
    assert not summary["terms"]["rrw"]["resolved"]
    assert summary["dwell"]["source"] == "fit"
    assert summary["bias_instability_deg_h"] > 0 or summary["rrw_deg_h_rt_h"] > 0
    noise = GyroNoise(
        arw_deg_rt_h=summary["arw_deg_rt_h"],
        bias_instability_deg_h=summary["bias_instability_deg_h"],
        rrw_deg_h_rt_h=summary["rrw_deg_h_rt_h"],
    )
    truth = GyroNoise(arw_deg_rt_h=0.005, bias_instability_deg_h=0.02, rrw_deg_h_rt_h=0.05)
    # a heading's σ from four 10-minute positions: the stored model's near the truth's
    # (within the scatter of one 2.5 h record), N alone's far under it
    stored_sigma = four_position_sigma(noise, 10.0, 600.0, 10.0)
    true_sigma = four_position_sigma(truth, 10.0, 600.0, 10.0)
    white_sigma = four_position_sigma(GyroNoise(arw_deg_rt_h=0.005), 10.0, 600.0, 10.0)
    assert stored_sigma == pytest.approx(true_sigma, rel=0.35)
    assert white_sigma < 0.6 * true_sigma
