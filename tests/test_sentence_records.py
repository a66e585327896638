"""A VectorNav's ASCII sentences captured from its serial port ("$VNYMR,…*CS" per line):
read as a record whose columns are the manual's fields, the gyro's axes offered by name
in rad/s, sentences of another kind, cut ones and those whose checksum fails left out
and said.  The captures are written here from the tests' own generator, their checksums
computed here (the XOR, and the manual's CRC-16 algorithm written out bit by bit)."""

from __future__ import annotations

import json
import math
from functools import reduce

import numpy as np
import pytest

from app.core.record_kinds import written_as_a_record
from app.core.sentence_records import checksum_holds, is_sentence_record
from app.core.static_record import read_static_record
from app.core.text_files import text_lines
from tests.noise_sources import static_record

RAD_S = math.radians(1.0) / 3600.0  # 1 °/h in rad/s
RATE_HZ = 40.0  # the VN-100's default asynchronous output rate
ARW = 0.3  # °/√h: a MEMS IMU's
MAG, ACCEL = "+00.1234,-00.5678,+00.1234", "-00.012,+00.034,-09.801"


def xor_checksum(body: str) -> str:
    return f"{reduce(lambda value, char: value ^ ord(char), body, 0):02X}"


def crc16_ccitt(body: str) -> str:
    """The 16-bit CRC as VectorNav's manual computes it, byte by byte."""
    crc = 0
    for byte in body.encode():
        crc = ((crc >> 8) | (crc << 8)) & 0xFFFF
        crc ^= byte
        crc ^= (crc & 0xFF) >> 4
        crc ^= (crc << 12) & 0xFFFF
        crc ^= ((crc & 0xFF) << 5) & 0xFFFF
    return f"{crc:04X}"


def capture(kind: str = "VNYMR", hours: float = 0.25, crc: bool = False, seed: int = 3):
    """A capture of ``kind`` sentences: the z axis the generator's white noise about
    10 °/h, x and y smaller, in rad/s to six decimals as the VN-100 writes them."""
    z = static_record(hours, RATE_HZ, arw=ARW, seed=seed) * RAD_S
    lines = []
    for k, rate in enumerate(z):
        gyro = f"{rate * 0.3:+010.6f},{rate * 0.5:+010.6f},{rate:+010.6f}"
        if kind == "VNYMR":  # yaw, pitch, roll; magnetic field; acceleration; rates
            body = f"VNYMR,+010.123,-001.234,+000.567,{MAG},{ACCEL},{gyro}"
        else:  # VNIMU: the case temperature rising through the capture, the pressure
            body = f"VNIMU,{MAG},{ACCEL},{gyro},{25 + k * 1e-4:+05.1f},+084.322"
        check = crc16_ccitt(body) if crc else xor_checksum(body)
        lines.append(f"${body}*{check}")
    return lines, z


def read(lines: list[str], column: str | None = "gyro_z (rad/s)"):
    data = ("\r\n".join(lines) + "\r\n").encode()
    return read_static_record(text_lines(data), column=column)


def notes_of(record) -> dict:
    return {note["key"]: note["params"] for note in record.notes}


@pytest.mark.parametrize("crc", [False, True], ids=["xor", "crc16"])
def test_a_vn100s_capture_is_read_as_its_gyro_axes(crc):
    from app.core.allan import analyse_record

    lines, z = capture(crc=crc)
    record = read(lines)
    assert record.unit == "rad/s"
    np.testing.assert_allclose(record.values, np.round(z, 6), atol=1e-12)
    assert notes_of(record)["allan.note_sentences"] == {
        "kind": "VNYMR",
        "first": 1,
        "last": len(lines),
    }
    result = analyse_record(record, RATE_HZ)
    assert result.arw_deg_rt_h == pytest.approx(ARW, rel=0.05)
    with pytest.raises(Exception) as choose:  # three axes: which, asked by name
        read(lines, column=None)
    assert choose.value.choices == ["gyro_x (rad/s)", "gyro_y (rad/s)", "gyro_z (rad/s)"]


def test_cut_other_and_broken_sentences_are_left_out_and_said():
    lines, z = capture(hours=0.05)
    lines[0] = lines[0][25:]  # the capture began mid-sentence
    broken = lines[100].replace("+", "-", 3)  # a bit flipped on the wire
    lines[100] = broken
    lines.insert(200, "$VNERR,03*" + xor_checksum("VNERR,03"))
    record = read(lines)
    kept = np.delete(np.round(z, 6), [0, 100])
    np.testing.assert_allclose(record.values, kept, atol=1e-12)
    notes = notes_of(record)
    assert notes["allan.note_sentences_checksum"] == {"n": 1, "line": 101}
    assert notes["allan.note_sentences_other"] == {"n": 2, "line": 1, "kind": "VNYMR"}
    assert "allan.note_comment_header" not in notes
    from app.web.i18n import translate

    for language, words in (("en", "1 sentence whose checksum"), ("zh-CN", "校验和不符")):
        key = "allan.note_sentences_checksum"
        assert words in translate(key, language, **notes[key])


def test_a_vnimu_capture_carries_the_case_temperature():
    lines, _ = capture("VNIMU", hours=0.05)
    record = read(lines)
    assert record.temperatures_c is not None
    assert record.temperatures_c[0] == pytest.approx(25.0)


def test_sentences_of_a_kind_the_manual_does_not_list_are_numbered_fields():
    bodies = [f"GYRO,{k},{10 + 0.01 * (k % 7):.3f}" for k in range(300)]
    lines = [f"${body}*{xor_checksum(body)}" for body in bodies]
    record = read(lines, column="field 2")
    assert record.values[:3].tolist() == [10.0, 10.01, 10.02]


def test_what_is_and_is_not_a_capture():
    lines, _ = capture(hours=0.01)
    assert is_sentence_record([lines[0][30:], *lines[1:20]])
    assert written_as_a_record("\n".join(lines[:30]))
    assert not is_sentence_record(["time_s,value", "0.0,10.74", "0.1,10.65"])
    assert not is_sentence_record(["$VNYMR,1,2*00", "10.74", "10.65", "10.70"])
    body = "VNYMR,+010.123"
    assert checksum_holds(f"${body}*{xor_checksum(body)}", xor_checksum(body))
    assert checksum_holds(f"${body}*{crc16_ccitt(body)}", crc16_ccitt(body))
    wrong = f"{int(xor_checksum(body), 16) ^ 1:02X}"
    assert not checksum_holds(f"${body}*{wrong}", wrong)


def test_the_lab_page_offers_the_axes_and_saves_the_one_chosen(client, student):
    from sqlmodel import select

    from app.db import read_session
    from app.lab.samples import unpack
    from app.models import SampleChunk
    from tests.factories import login, new_session, post_json

    assert login(client, "student1").status_code == 303
    session_id = new_session(client)
    page = f"/lab/sessions/{session_id}"
    lines, z = capture(hours=0.02)
    lines[0] = lines[0][40:]
    text = "\r\n".join(lines) + "\r\n"
    body = {"part": "heading", "unit": "rad/s", "text": text}
    preview = post_json(client, f"{page}/csv/preview", body, page).json()
    assert [c["value"] for c in preview["columns"]][0] == "gyro_x (rad/s)"
    assert any("$VNYMR sentences" in note for note in preview["notes"])
    assert any("line the capture cut" in note for note in preview["notes"])
    chosen = {**body, "column": "gyro_z (rad/s)", "position": 2}
    saved = post_json(client, f"{page}/csv", chosen, page)
    assert saved.status_code == 200 and saved.json()["saved"] == [2]
    with read_session() as db:
        chunk = db.exec(select(SampleChunk)).one()
    np.testing.assert_allclose(unpack(chunk.values), np.round(z[1:], 6) / RAD_S, rtol=1e-12)


def test_gyrolab_allan_reads_it_and_solve_refuses_it(capsys, tmp_path):
    from app.cli.main import main

    lines, _ = capture(hours=0.1)
    path = tmp_path / "vn100.txt"
    path.write_text("\r\n".join(lines) + "\r\n")
    assert main(["allan", str(path), "--rate", "40", "--column", "gyro_z", "--json"]) == 0
    out, _ = capsys.readouterr()
    assert json.loads(out)["arw_deg_rt_h"] == pytest.approx(ARW, rel=0.08)
    assert main(["solve", "heading", str(path)]) == 2
    assert "is one position's record" in capsys.readouterr().err
