"""The serial bridge end to end: pseudo-terminals written like real FOGs at their baud
rates, into a session with the gyro's own times; retries; record and replay; the
command line's messages and exit status."""

from __future__ import annotations

import json
import os
import re
import threading
import time

import httpx
import numpy as np
import pytest
from sqlmodel import select

from app.bridge.instruments import Instrument, set_up
from app.bridge.lines import LineParser
from app.bridge.recording import Recorder, open_recording, paced
from app.bridge.run import SampleTable, run_bridge
from app.bridge.samples import SampleMaker
from app.bridge.sources import serial_chunks
from app.bridge.upload import Uploader
from app.cli.main import main
from app.core.exceptions import UserError
from app.core.readings import parse_readings_csv
from app.db import read_session
from app.lab.exports import Selection, session_json
from app.lab.result_flags import quality_flags
from app.lab.results import current_data
from app.lab.store import load_samples
from app.models import LabSession, Take
from tests.factories import PRACTICE, english, token_for
from tests.instrument_streams import dsp1750_stream, dsp3000_lines

FOG_LINE = re.compile(r"^\$FOG,\d+,(?P<value>[-+0-9.eE]+),")
RATES = 15.0 + 0.3 * np.cos(np.arange(500) / 25.0)


def fog_lines(values, garbage_every=7):
    """What a FOG with an RS-232 output prints: a sentence per reading, some noise lines."""
    for index, value in enumerate(values):
        if index % garbage_every == 3:
            yield "$STATUS,OK,TEMP=24.1\r\n"
        yield f"$FOG,{index},{value / 3600:.9f},24.1*5A\r\n"


def test_line_parser():
    parser = LineParser(regex=FOG_LINE, scale=3600.0)
    assert parser.parse("$FOG,1,0.0029750,24.1*5A") == pytest.approx(10.71)
    assert parser.parse("$STATUS,OK") is None and parser.skipped == 1
    assert parser.parse("") is None and parser.skipped == 1
    by_column = LineParser(column=2)
    assert by_column.parse("12:00:01, 10.65, 24.0") == 10.65
    assert by_column.parse("12:00:01;  -8.83") == -8.83
    assert by_column.parse("only") is None
    assert LineParser(column=1).parse("nan") is None


@pytest.fixture
def api_session(client, student):
    headers = token_for(client, "student1")
    client.headers.update(headers)
    session_id = client.post("/api/v1/sessions", json=PRACTICE).json()["id"]
    return client, session_id


def stored(session_id) -> tuple[np.ndarray, np.ndarray | None]:
    with read_session() as db:
        take = db.exec(select(Take).where(Take.session_id == session_id)).one()
        return load_samples(db, take)


def pty_instrument(pieces: list[bytes], per_write: int, pause_s: float):
    """A pseudo-terminal whose far end writes ``per_write`` pieces every ``pause_s``
    (the instrument's own pace); returns (port name, start, finish)."""
    master, slave = os.openpty()

    def write():
        for start in range(0, len(pieces), per_write):
            os.write(master, b"".join(pieces[start : start + per_write]))
            time.sleep(pause_s)

    writer = threading.Thread(target=write, daemon=True)

    def finish():
        writer.join(10)
        os.close(master)
        os.close(slave)

    return os.ttyname(slave), writer.start, finish


def bridge_into(client, session_id, port_chunks, instrument, *, mid_line=True, **limits):
    setup = set_up(instrument, mid_line=mid_line)
    maker = SampleMaker(setup.unit, setup.rate_hz, start_s=36000.0)
    uploader = Uploader(client, session_id, "heading", 1, batch=100)
    outcome = run_bridge(port_chunks, setup, maker, uploader=uploader, **limits)
    return outcome


def test_a_dsp1750_at_921600_baud_reaches_the_session_with_its_own_times(api_session):
    client, session_id = api_session
    frames = dsp1750_stream(RATES)
    port, start, finish = pty_instrument(frames, per_write=10, pause_s=0.01)  # 1000 Hz
    chunks = serial_chunks(port, 921600)  # opened before the gyro talks
    start()
    try:
        outcome = bridge_into(
            client, session_id, chunks, Instrument("kvh-dsp1750"), max_samples=500, seconds=30
        )
    finally:
        finish()
    assert outcome.samples == outcome.stored == 500 and not outcome.gapped
    assert outcome.temperatures == [30.0, 30.0]
    exported = json.loads("".join(session_json(Selection(session_id))))  # temperature kept
    assert exported["positions"][0]["temperatures_c"] == [30.0] * 500
    values, times = stored(session_id)
    assert values == pytest.approx(RATES, rel=1e-6)
    assert times == pytest.approx(36000.0 + np.arange(500) / 1000.0)  # the gyro's clock


def test_a_dsp3000_at_38400_baud_with_a_fault_line_is_stored_with_the_gap(api_session):
    client, session_id = api_session
    lines = dsp3000_lines(RATES[:120] / 3600.0, faults={30})
    port, start, finish = pty_instrument(lines, per_write=1, pause_s=0.002)
    chunks = serial_chunks(port, 38400)
    start()
    try:
        outcome = bridge_into(
            client, session_id, chunks, Instrument("kvh-dsp3000"), max_samples=118, seconds=30
        )
    finally:
        finish()
    # a port may open mid-line, so its first line is never trusted
    assert outcome.stats.garbage_bytes == len(lines[0])
    assert outcome.stored == 118 and outcome.stats.faults == 1 and outcome.gapped
    values, times = stored(session_id)
    assert values == pytest.approx(np.delete(RATES[:120], [0, 30]), abs=0.002)
    assert np.diff(times).max() == pytest.approx(0.02)  # 100 Hz, one line missing
    with read_session() as db:  # the session flags the gap to the student and the teacher
        session = db.get(LabSession, session_id)
        flags = quality_flags(session, current_data(db, session)["heading"])
    assert {"key": "flag.gaps", "params": {"position": 1, "n": 1, "missing": 1}} in flags


def test_a_text_gyro_on_a_pseudo_terminal(api_session):
    client, session_id = api_session
    values = np.round(10.7 + 0.1 * np.sin(np.arange(120)), 4)
    lines = [line.encode() for line in fog_lines(values)]
    port, start, finish = pty_instrument(lines, per_write=1, pause_s=0.002)
    chunks = serial_chunks(port, 115200)
    start()
    try:
        instrument = Instrument("text", regex=FOG_LINE, scale=3600.0)
        outcome = bridge_into(client, session_id, chunks, instrument, max_samples=119, seconds=30)
    finally:
        finish()
    assert outcome.stored == 119  # the first line is never trusted (the port may open mid-line)
    stored_values, times = stored(session_id)
    assert stored_values == pytest.approx(values[1:], abs=1e-5) and times is None
    assert outcome.stats.frames == 119


class LosesAnswers(httpx.BaseTransport):
    """Delivers every request, but the answer of every third one is lost on the way back."""

    def __init__(self, inner: httpx.BaseTransport) -> None:
        self.inner = inner
        self.count = 0

    def handle_request(self, request: httpx.Request) -> httpx.Response:
        self.count += 1
        response = self.inner.handle_request(request)
        if self.count % 3 == 2:
            response.read()
            raise httpx.ReadError("connection reset", request=request)
        return response


@pytest.mark.parametrize("binary", [True, False])
def test_retries_never_duplicate_samples_or_times(api_session, binary):
    client, session_id = api_session
    client._transport = LosesAnswers(client._transport)
    uploader = Uploader(client, session_id, "latitude", 2, batch=10, backoff_s=0.001, binary=binary)
    for index in range(100):
        uploader.add(index / 10, 500.0 + index / 100)
    uploader.flush()
    assert uploader.sent == 100 and uploader.attempts > 10  # some batches were sent twice
    values, times = stored(session_id)
    assert values.tolist() == [index / 10 for index in range(100)]
    assert times == pytest.approx(500.0 + np.arange(100) / 100)


def test_refused_upload_is_reported(api_session):
    client, session_id = api_session
    uploader = Uploader(client, session_id, "heading", 1, unit="deg/s", batch=5)
    with pytest.raises(UserError, match="check the unit") as caught:
        for _ in range(5):
            uploader.add(10.7)
    assert caught.value.key == "bridge.refused"


def test_record_then_replay_gives_the_same_samples(tmp_path):
    frames = dsp1750_stream(RATES[:300])
    del frames[100]  # a frame lost on the wire during the recording
    pieces = [b"".join(frames[i : i + 7]) for i in range(0, len(frames), 7)]
    instrument = Instrument("kvh-dsp1750")
    recording = tmp_path / "run.gyroraw"
    recorder = Recorder(recording, {"format": "kvh-dsp1750", "wall_clock_s": 0.0})
    setup = set_up(instrument)
    live = run_bridge(
        ((i * 0.007, piece) for i, piece in enumerate(pieces)),
        setup,
        maker := SampleMaker(setup.unit, setup.rate_hz),
        recorder=recorder,
        table=SampleTable(tmp_path / "live.csv", 1, timed=True, temperature=True),
    )
    assert live.samples == 299 and maker.absent == 1
    opened = open_recording(recording)
    assert opened.meta["format"] == "kvh-dsp1750"
    setup = set_up(instrument)
    replayed = run_bridge(
        paced(opened.chunks(), 0),
        setup,
        SampleMaker(setup.unit, setup.rate_hz),
        table=SampleTable(tmp_path / "replayed.csv", 1, timed=True, temperature=True),
    )
    assert replayed.samples == 299 and replayed.absent == 1 and not opened.truncated
    live_csv = (tmp_path / "live.csv").read_text()
    assert live_csv == (tmp_path / "replayed.csv").read_text()
    readings = parse_readings_csv(live_csv)  # the CSV is GyroLab's long layout
    assert readings.positions[0] == pytest.approx(np.delete(RATES[:300], 100), rel=1e-6)
    assert readings.temperatures_c[0][0] == 30.0


def test_a_replay_keeps_the_recorded_pace(tmp_path):
    recording = tmp_path / "paced.gyroraw"
    recorder = Recorder(recording, {})
    for index in range(5):
        recorder.write(index * 0.1, b"x")
    recorder.close()
    slept = []
    chunks = list(paced(open_recording(recording).chunks(), 2.0, sleep=slept.append))
    assert [seconds for seconds, _ in chunks] == pytest.approx([0, 0.1, 0.2, 0.3, 0.4])
    # (the fake sleep does not pass time) each chunk is due at its recorded time / 2
    assert slept == pytest.approx([0.05, 0.1, 0.15, 0.2], abs=0.01)


def test_truncated_and_foreign_recordings(tmp_path):
    recording = tmp_path / "cut.gyroraw"
    recorder = Recorder(recording, {"format": "kvh-dsp1750"})
    recorder.write(0.0, b"".join(dsp1750_stream(RATES[:10])))
    recorder.close()
    whole = recording.read_bytes()
    recording.write_bytes(whole[:-50])  # the recorder was killed mid-write
    opened = open_recording(recording)
    assert len(b"".join(chunk for _, chunk in opened.chunks())) == 10 * 36 - 50
    assert opened.truncated
    for bad in (b"PK\x03\x04zip", b"GYROLAB-RAW 1\n[1, 2]\n", b"GYROLAB-RAW 1\n{\xff\n"):
        recording.write_bytes(bad)
        with pytest.raises(UserError) as caught:
            open_recording(recording)
        assert caught.value.key == "bridge.bad_recording"
    recording.write_bytes(b"GYROLAB-RAW 1\n{}\n" + b"\x00" * 8 + b"\xff\xff\xff\x7f")
    with pytest.raises(UserError) as caught:
        list(open_recording(recording).chunks())
    assert "damaged" in english(caught.value)


def test_the_command_line_replays_checks_and_explains(tmp_path, capsys):
    frames = dsp1750_stream(RATES[:200])
    recording = tmp_path / "class-run.gyroraw"
    recorder = Recorder(
        recording, {"format": "kvh-dsp1750", "wall_clock_s": 1_700_000_000.0, "mid_line": True}
    )
    recorder.write(0.0, b"".join(frames[:50]))
    recorder.write(0.05, b"".join(frames[51:]))  # frame 50 never arrived
    recorder.close()
    table = tmp_path / "samples.csv"
    code = main(
        [
            "bridge",
            "--replay",
            str(recording),
            "--speed",
            "0",
            "--csv",
            str(table),
            "--language",
            "en",
        ]
    )
    report = capsys.readouterr().err
    assert code == 3  # finished, but the record has a gap
    assert "199 frames read, 199 samples made" in report
    assert "samples missing: 1, in gaps: 1" in report and "Temperature 30.00 to 30.00 °C" in report
    assert table.read_text().count("\n") == 200  # header + 199 rows
    code = main(
        ["bridge", "--replay", str(recording), "--format", "frame:hdr=zz", "--language", "zh-CN"]
    )
    assert code == 2 and "帧描述有误" in capsys.readouterr().err
    code = main(["bridge", "--replay", str(tmp_path / "nothing"), "--language", "en"])
    assert code == 2 and "cannot read" in capsys.readouterr().err
    code = main(["bridge", "--replay", str(recording), "--session", "5", "--language", "en"])
    assert code == 2 and "--part and --position" in capsys.readouterr().err
    code = main(["bridge", "--serial", str(tmp_path / "no-such-port"), "--language", "en"])
    assert code == 2 and "cannot open" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("option", "words"),
    [
        (["--rate", "0"], "--rate must be a sample rate above 0 Hz"),  # was a TypeError
        (["--rate", "nan"], "--rate must be a finite number"),  # NaN times in the CSV
        (["--rate", "-5"], "--rate must be a sample rate above 0 Hz"),  # times going back
        (["--scale", "nan"], "--scale must be a finite number"),  # every reading dropped
        (["--scale", "0"], "--scale must not be 0"),
        (["--temp-scale", "inf"], "--temp-scale must be a finite number"),
        (["--column", "-3"], "--column must be a whole number of at least 1"),  # all dropped
        (["--batch", "0"], "--batch must be a whole number of at least 1"),
        (["--max-samples", "-1"], "--max-samples must be a whole number of at least 1"),
        (["--baud", "-1"], "--baud must be a whole number of at least 1"),
        (["--speed", "-1"], "--speed must not be negative"),
        (["--seconds", "0"], "--seconds must be above 0"),
    ],
)
def test_an_option_the_bridge_cannot_use_is_refused_before_anything_is_written(
    tmp_path, capsys, option, words
):
    source = tmp_path / "gyro.txt"
    source.write_text("10.1\n10.2\n10.3\n")
    table = tmp_path / "samples.csv"
    code = main(["bridge", "--file", str(source), "--csv", str(table), *option, "--language", "en"])
    assert code == 2 and words in capsys.readouterr().err
    assert not table.exists()
    assert main(["bridge", "--file", str(source), *option, "--language", "zh-CN"]) == 2
    assert re.search("[\u4e00-\u9fff]", capsys.readouterr().err)


@pytest.mark.parametrize(
    ("description", "field"),
    [
        ('{"format": "text", "rate_hz": "fast"}', "rate_hz"),  # each of these a traceback
        ('{"format": "text", "rate_hz": 0}', "rate_hz"),
        ('{"format": "text", "wall_clock_s": 1e300}', "wall_clock_s"),
        ('{"format": "text", "wall_clock_s": NaN}', "wall_clock_s"),
        ('{"format": "text", "wall_clock_s": [1]}', "wall_clock_s"),
        ('{"format": "text", "scale": "big"}', "scale"),
        ('{"format": "text", "regex": 5}', "regex"),
        ('{"format": ["text"]}', "format"),
        ('{"format": "vectornav", "axis": "w"}', "axis"),
        ('{"format": "text", "column": "two"}', "column"),
        ('{"format": "text", "mid_line": "no"}', "mid_line"),
    ],
)
def test_a_recordings_damaged_description_is_named(tmp_path, capsys, description, field):
    recording = tmp_path / "edited.gyroraw"
    recording.write_bytes(b"GYROLAB-RAW 1\n" + description.encode() + b"\n")
    with pytest.raises(UserError) as caught:
        open_recording(recording)
    assert (caught.value.key, caught.value.params["field"]) == ("bridge.damaged_description", field)
    code = main(["bridge", "--replay", str(recording), "--speed", "0", "--language", "en"])
    assert code == 2 and f"damaged: {field} = " in capsys.readouterr().err


def test_a_description_nested_too_deep_is_a_damaged_recording(tmp_path):
    recording = tmp_path / "deep.gyroraw"
    recording.write_bytes(b"GYROLAB-RAW 1\n" + b"[" * 5000 + b"]" * 5000 + b"\n")
    with pytest.raises(UserError) as caught:
        open_recording(recording)  # was a RecursionError
    assert caught.value.key == "bridge.bad_recording"


def test_a_recording_remembers_how_it_was_read(tmp_path, capsys, monkeypatch):
    """``--record`` keeps the format and its options; a replay needs only the file."""
    source = tmp_path / "gyro.bin"
    source.write_bytes(b"".join(dsp3000_lines(RATES[:40] / 3600.0)))
    recording = tmp_path / "gyro.gyroraw"
    code = main(
        [
            "bridge",
            "--file",
            str(source),
            "--format",
            "kvh-dsp3000",
            "--rate",
            "50",
            "--record",
            str(recording),
            "--language",
            "en",
        ]
    )
    assert code == 0 and "40 frames read" in capsys.readouterr().err
    meta = open_recording(recording).meta
    assert meta["format"] == "kvh-dsp3000" and meta["rate_hz"] == 50 and meta["mid_line"] is False
    assert json.loads(json.dumps(meta)) == meta
    table = tmp_path / "replayed.csv"
    assert main(["bridge", "--replay", str(recording), "--speed", "0", "--csv", str(table)]) == 0
    replayed = parse_readings_csv(table.read_text())
    assert replayed.positions[0] == pytest.approx(RATES[:40], abs=0.002)
    assert np.diff(replayed.times_s[0]) == pytest.approx(np.full(39, 0.02))
