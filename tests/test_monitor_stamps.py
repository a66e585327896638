"""A record captured through the Arduino IDE's serial monitor with its timestamps shown
("10:00:00.123 -> 10.74"): the stamps read as the record's clock, the rest of each line
as it would be read without them -- plain rates, several columns, a decimal comma, a
VectorNav's sentences.  The captures are written here from the tests' own generator."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.core.monitor_stamps import is_stamped_capture, unstamped_lines
from app.core.record_kinds import written_as_a_record
from app.core.static_record import read_static_record
from app.core.text_files import text_lines
from tests.noise_sources import static_record
from tests.test_sentence_records import capture

ARW = 0.05  # °/√h: a FOG's angle random walk


def stamp(seconds: float) -> str:
    hours, rest = divmod(36_000.0 + seconds, 3600.0)
    minutes, secs = divmod(rest, 60.0)
    return f"{int(hours):02d}:{int(minutes):02d}:{secs:06.3f}"


def stamped(lines: list[str], rate_hz: float) -> str:
    return "".join(f"{stamp(k / rate_hz)} -> {line}\r\n" for k, line in enumerate(lines))


def read(text: str, column: str | None = None):
    return read_static_record(text_lines(text.encode()), column=column)


def test_a_stamped_capture_of_rates_is_analysed_on_the_monitors_clock():
    from app.core.allan import analyse_record

    rates = static_record(1.0, 10.0, arw=ARW, seed=4)
    text = stamped([f"{rate:.4f}" for rate in rates], 10.0)
    assert is_stamped_capture(text.splitlines()[:20]) and written_as_a_record(text[:2000])
    record = read(text)
    np.testing.assert_allclose(record.values, np.round(rates, 4))
    np.testing.assert_allclose(record.times_s[:3], [0.0, 0.1, 0.2], atol=1e-9)
    assert any(note["key"] == "allan.note_monitor_stamps" for note in record.notes)
    result = analyse_record(record, None)  # the rate from the stamps
    assert result.rate_hz == pytest.approx(10.0, rel=1e-6)
    assert result.arw_deg_rt_h == pytest.approx(ARW, rel=0.05)


@pytest.mark.parametrize(
    ("rest", "expected"),
    [
        ("10,74", "10:00:00.000\t10,74"),  # a decimal comma stays in its cell
        ("12.3,4.5,6.7", "10:00:00.000,12.3,4.5,6.7"),
        ("12,3;4,5", "10:00:00.000;12,3;4,5"),
        ("12.3\t4.5", "10:00:00.000\t12.3\t4.5"),
        ("12.3 4.5", "10:00:00.000 12.3 4.5"),
        ("", ""),  # an empty line the device sent
    ],
)
def test_the_stamp_is_joined_by_the_lines_own_separator(rest, expected):
    [line] = unstamped_lines([f"10:00:00.000 -> {rest}"])
    assert line.rstrip("\n") == expected


def test_a_stamped_capture_of_three_columns_with_decimal_commas():
    rates = static_record(0.05, 10.0, arw=ARW, seed=5)
    lines = [f"{k};{rate:.4f};25,0".replace(".", ",") for k, rate in enumerate(rates)]
    record = read(stamped(lines, 10.0), column="3")  # the stamp is the first column
    np.testing.assert_allclose(record.values, np.round(rates, 4))


def test_a_vectornav_captured_through_the_monitor_keeps_its_stamps_as_times():
    lines, z = capture(hours=0.02)
    record = read(stamped(lines, 40.0), column="gyro_z (rad/s)")
    np.testing.assert_allclose(record.values, np.round(z, 6), atol=1e-12)
    np.testing.assert_allclose(np.diff(record.times_s[:4]), [0.025] * 3, atol=1e-9)
    keys = {note["key"] for note in record.notes}
    assert {"allan.note_monitor_stamps", "allan.note_sentences"} <= keys


def test_what_is_no_stamped_capture():
    assert not is_stamped_capture(["time_s,value", "0.0,10.74", "0.1,10.65"])
    assert not is_stamped_capture(["10:00:00.000,10.74", "10:00:00.100,10.65"])
    assert not is_stamped_capture(["10:00:00.000 -> 10.74", "x", "y", "z"])


def test_the_lab_page_saves_a_stamped_position_with_its_times(client, student):
    from sqlmodel import select

    from app.db import read_session
    from app.lab.samples import unpack
    from app.models import SampleChunk
    from tests.factories import login, new_session, post_json

    assert login(client, "student1").status_code == 303
    session_id = new_session(client)
    page = f"/lab/sessions/{session_id}"
    rates = 10.0 + static_record(1 / 60, 10.0, arw=ARW, seed=6)
    body = {"part": "heading", "unit": "deg/h", "text": stamped([f"{r:.4f}" for r in rates], 10.0)}
    preview = post_json(client, f"{page}/csv/preview", body, page).json()
    assert preview["layout"] == "record" and preview["positions"][0]["n"] == rates.size
    assert any("serial monitor" in note for note in preview["notes"])
    client.cookies.set("gyrolab_lang", "zh-CN")
    zh = post_json(client, f"{page}/csv/preview", body, page).json()
    assert any("串口监视器" in note for note in zh["notes"])
    assert post_json(client, f"{page}/csv", {**body, "position": 3}, page).status_code == 200
    with read_session() as db:
        chunk = db.exec(select(SampleChunk)).one()
    np.testing.assert_allclose(unpack(chunk.times)[:3], [0.0, 0.1, 0.2], atol=1e-9)
    assert math.isclose(float(np.mean(unpack(chunk.values))), float(np.mean(np.round(rates, 4))))


def test_a_stamp_that_goes_back_is_said_not_a_500():
    """The PC's clock stepped back under the monitor (a time server's correction): its
    stamps do not rise.  A bare first column that goes back is taken for a counter that
    wraps and dropped -- a clock's stamps are none, and reading them was an
    AttributeError; now the record's times are refused in words."""
    from app.core.exceptions import UserError

    lines = [f"{rate:.4f}" for rate in static_record(0.02, 10.0, arw=ARW, seed=7)]
    text = stamped(lines, 10.0).splitlines()
    text[200] = "10:00:00.500 -> 10.0000"
    with pytest.raises(UserError) as refused:  # the rates' column chosen: the stamps guessed
        read("\n".join(text) + "\n", column="2")
    assert refused.value.key == "allan.bad_times"
    from app.core.allan import analyse_record

    with pytest.raises(UserError) as refused:  # found by name: refused where it is analysed
        analyse_record(read("\n".join(text) + "\n"), None)
    assert refused.value.key == "allan.bad_times"
