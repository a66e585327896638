"""A static gyro record saved by MATLAB (``.mat``, what ``save`` writes by default), as
MATLAB's own Allan-variance example keeps one (``omega`` in rad/s beside its rate ``Fs``):
read for the teacher's characterisation and ``gyrolab allan`` as a text record would be --
the rate the file states used and said, a time vector as the times, an IMU's axes offered
-- and a file GyroLab cannot read (``-v7.3``, damaged, no vector) refused in words."""

from __future__ import annotations

import base64
import io
import math

import numpy as np
import pytest
import scipy.io

from app.core import matlab_files
from app.core.allan import analyse_record
from app.core.exceptions import UserError
from app.core.matlab_files import is_matlab_file, matlab_record
from app.core.record_columns import ColumnChoiceNeeded
from app.web.i18n import translator
from tests.noise_sources import static_record
from tests.test_characterisation import shown, stored, upload
from tests.test_characterisation import world as world  # noqa: F401 -- the fixture

ARW = 0.02  # °/√h
RATE_HZ = 50.0
DEG_H_PER_RAD_S = 3600.0 * 180.0 / math.pi
# a valid file (``omega`` and ``Fs``, saved uncompressed) with a few bytes changed, as a
# fuzzer changed them: scipy 1.17's compiled reader dies of a segmentation fault on it
CRASHING_MAT = base64.b64decode(
    "0kFUTEFCIDUuMCBNQVQtZmlsZSBQbGF0Zm9ybTogcG9zaXgsIENyZWF0ZWQgb246IE1vbiBEZWMgIDcgMjE6MDY6"
    "MDAgMjAyNgAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAABSU0OAAAA"
    "WAMAAAYAAAAIAAAABgAAAAAAAAAFAAAACAAAAAEAAABkAAAAAQAAAAUAAABvbWVnYQAAACQAAAAgAwAAAAAAAAAA"
    "AAAAAAAAAADwPwAAAAAAAABAAAAAAAAACEAAAAAAAAAQQAAAAAAAABRAAAAAAAAAGEAAAAAAAAAcQAAAAAAAACBA"
    "AAAAAAAAIkAAAAAAAAAkQAAAAAAAACZAAAAAAAAAKEAAAAAAAAAqQAAAAAAAACxAAAAAAAAALkAAAAAAAAAwQAAA"
    "AAAAADFAAAAAAIcAMkAAAAAAAAAzQAAAAAAAADRAAAAAAAAANUAAAAAAAAA2QAAAAAAAADdAAAAAAAAAOEAAAAAA"
    "AAA5QAAAAAAAADpAAAAAAAAAO0AAAAAAAAA8QAAAAAAAAD1AAAAAAAAAPkAAAAAAAAA/QAAAAAAAAEBAAAAAAACA"
    "QEAAAAAAAABBQAAAAAAAgEFAAAAAAAAAQkAAAAAAAIBCQAAAAAAAAENAAAAAAACAQ0AAAAAAAABEQAAAAAAAgERA"
    "AAAAAAAARUAAAAAAAIBFQAAAAAAAAEZAAAAAAACARkAAAAAAAABHQAAAAAAAgEdAAAAAAAAASEAAAAAAAIBIQAAA"
    "AAAAAElAAAAAAACASUAAAAAAAABKQAAAAAAAgEpAAAAAAAAAS0AAAAAAAIBLQAAAAACTAExAAAAAAACATEAAAAAA"
    "AABNQAAAAAAAgE1AAAAAAAAATkAAAAAAAIBOQAAAAAAAAE9AAAAAAACAT0AAAAAAAABQQAAAAAAAQFBAAAAAAACA"
    "UEAAAAAAAMBQQAAAAAAAAFFAAAAAAABAUUAAAAAAAIBRQAAAAABkwFFAAAAAAAAAUkAAAAAAAEBSQAAAAAAAgFJA"
    "AAAAAADAUkAAAAAAAABTQAAAAAAAQFNAAAAAAACAU0AAAAAAAMBTQAAAAAAAAFRAAAAAAABAVEAAAAAAAIBUQAAA"
    "AAAAwFRAAAAAAAAAVUAAAAAAAEBVQAAAAAAAgFVAAAAAAADAVUAAAAAAAABWQAAAAAAAQFZAAE0AAACAVkAAAAAA"
    "AMBWQAAAAAAAAFdAAAAAAABAV0AAAAAAAIBXQAAAAAAAwFdAAAAAAAAAWEAAAAAAAEBYQAAAAAAAgFhAAAAAAADA"
    "WEAOAAAAOAAAAAYAAAAIAAAABgAAAAAAAAAFAAAACAAAAAEAAAABAAAAAQACAEZzAAAJAAAACAAAAAAAAAAAACRA"
)


def saved(variables: dict, **options) -> bytes:
    out = io.BytesIO()
    scipy.io.savemat(out, variables, **options)
    return out.getvalue()


def gyro(hours: float = 1.0) -> np.ndarray:
    return static_record(hours, RATE_HZ, arw=ARW, seed=5, bias=3.0)  # °/h


def read(data: bytes, column: str | None = None):
    return matlab_record(data, column)


def test_matlabs_example_layout_omega_in_rad_per_s_beside_fs():
    rates = gyro(0.5)
    data = saved({"omega": (rates / DEG_H_PER_RAD_S).reshape(-1, 1), "Fs": RATE_HZ,
                  "info": "FOG on the bench"}, do_compression=True)  # fmt: skip
    assert is_matlab_file(data[:20]) and not is_matlab_file(b"time_s,value\n")
    record = read(data)
    assert record.times_s is None and record.stated_rate_hz == RATE_HZ
    assert record.values * DEG_H_PER_RAD_S == pytest.approx(rates, rel=1e-12)
    result = analyse_record(record, None, unit="rad/s")
    assert result.rate_hz == RATE_HZ
    assert result.arw_deg_rt_h == pytest.approx(ARW, rel=0.05)
    said = {note["key"]: note["params"] for note in result.notes}
    assert translator("en")("allan.note_matlab", **said["allan.note_matlab"]) == (
        "Read as a MATLAB data file (.mat): the readings are its vector omega."
    )
    assert translator("zh-CN")("allan.note_array_rate", **said["allan.note_array_rate"]) == (
        "没有时间，也没有填写采样率：使用了文件中的 Fs = 50 Hz。"
    )
    assert "allan.note_rate_stated" not in said  # no line above a table


def test_a_time_vector_is_the_records_times():
    rates = gyro(0.5)
    times = np.arange(rates.size) / RATE_HZ + 1000.0
    record = read(saved({"w": rates, "t": times}))
    assert record.times_s == pytest.approx(times)
    result = analyse_record(record, None)
    assert result.arw_deg_rt_h == pytest.approx(ARW, rel=0.05)
    assert result.notes[0] == {
        "key": "allan.note_matlab_times",
        "params": {"variable": "w", "time": "t"},
    }


def test_an_imus_axes_are_offered_and_one_is_read_by_its_name_or_number():
    rates = gyro(0.2)
    axes = np.column_stack([rates + 100.0, rates - 50.0, rates])
    data = saved({"gyro": axes, "acc": np.ones((rates.size, 3)), "fs": RATE_HZ})
    with pytest.raises(ColumnChoiceNeeded) as offered:
        matlab_record(data)
    assert offered.value.key == "matlab.choose_vector"
    assert offered.value.choices == ["gyro 1", "gyro 2", "gyro 3", "acc 1", "acc 2", "acc 3"]
    assert read(data, "Gyro 3").values == pytest.approx(rates)
    assert read(data, "3").values == pytest.approx(rates)
    with pytest.raises(UserError) as missing:
        read(data, "9")
    assert missing.value.key == "allan.no_such_column"


@pytest.mark.parametrize(
    ("data", "key"),
    [
        (b"MATLAB 7.3 MAT-file, Platform: GLNXA64" + bytes(200), "matlab.v73"),
        (saved({"w": np.arange(5000.0)})[:3000], "matlab.unreadable"),
        (saved({"name": "bench 3", "fs": 10.0, "short": np.arange(5.0)}), "matlab.no_record"),
    ],
)
def test_what_cannot_be_read_is_said_in_both_languages(data, key):
    with pytest.raises(UserError) as refused:
        matlab_record(data)
    assert refused.value.key == key
    for language in ("en", "zh-CN"):
        words = translator(language)(key, **refused.value.params)
        assert words and not words.startswith("matlab.")
    if key == "matlab.v73":
        assert "save('record.mat', '-v7')" in translator("en")(key)


def test_a_file_past_the_limit_is_refused_before_it_is_loaded(monkeypatch):
    monkeypatch.setattr(matlab_files, "MAX_ELEMENTS", 1000)
    with pytest.raises(UserError) as refused:
        matlab_record(saved({"w": np.zeros(2000)}, do_compression=True))
    assert refused.value.key == "matlab.too_large" and refused.value.params["limit"] == 1000


@pytest.mark.one_backend  # the file's reading; storing a characterisation is tested on both
def test_the_teacher_characterises_the_bench_from_a_mat_file(world):  # noqa: F811
    from tests.factories import browser

    teacher = browser(world, "teacher1")
    rates = gyro(1.0)
    data = saved({"omega": rates / DEG_H_PER_RAD_S, "Fs": RATE_HZ}, do_compression=True)
    asked = upload(teacher, world, data, rate="")  # °/h by default: no gyro's floor
    assert asked.status_code == 400 and "unit" in shown(teacher, asked)
    reply = upload(teacher, world, data, rate="", unit="rad/s")
    assert reply.status_code == 303, reply.text
    summary = stored(world)
    assert summary["rate_hz"] == RATE_HZ
    assert summary["arw_deg_rt_h"] == pytest.approx(ARW, rel=0.05)
    page = shown(teacher, reply)
    assert "the readings are its vector omega" in page and "Fs = 50 Hz was used" in page


def test_a_structs_fields_are_read_and_a_cell_array_passed_over():
    """A lab's script saves its record in a struct (``imu.gyro``, ``imu.fs``, ``imu.t``)
    beside a cell array of notes: the fields read by their own names, the cells passed
    over (before, the struct was no record and the cells could fail the reader)."""
    rates = gyro(0.2)
    cells = np.empty((1, 3), dtype=object)
    cells[0, 0], cells[0, 1], cells[0, 2] = np.arange(5.0), "bench 3", np.ones((2, 2))
    imu = {"gyro": np.column_stack([rates + 1.0, rates]), "fs": RATE_HZ}
    data = saved({"imu": imu, "notes": cells})
    with pytest.raises(ColumnChoiceNeeded) as offered:
        read(data)
    assert offered.value.choices == ["imu.gyro 1", "imu.gyro 2"]
    record = read(data, "imu.gyro 2")
    assert record.values == pytest.approx(rates) and record.stated_rate_hz == RATE_HZ
    assert record.rate_note["params"] == {"name": "imu.fs", "rate": "50"}
    timed = read(saved({"run": {"w": rates, "t": np.arange(rates.size) / RATE_HZ}}))
    assert timed.notes[0]["params"] == {"variable": "run.w", "time": "run.t"}
    with pytest.raises(UserError) as refused:
        read(saved({"notes": cells}))
    assert refused.value.key == "matlab.no_record"


def test_a_file_that_crashes_scipys_reader_is_refused_and_nothing_else_dies():
    """The loader runs in a process of its own: a crafted file that crashes scipy's
    compiled reader ends that process, and the file is refused in words -- the server, the
    command line and this test go on."""
    import subprocess
    import sys

    crash = subprocess.run(
        [sys.executable, "-c", "import io, sys; from scipy.io import loadmat; "
         "loadmat(io.BytesIO(sys.stdin.buffer.read()), squeeze_me=True, simplify_cells=True)"],
        input=CRASHING_MAT, capture_output=True, check=False,
    )  # fmt: skip
    assert crash.returncode != 0  # in-process, this file ends the process (or, fixed, raises)
    with pytest.raises(UserError) as refused:
        matlab_record(CRASHING_MAT)
    assert refused.value.key == "matlab.unreadable"
    assert read(saved({"omega": gyro(0.05), "Fs": RATE_HZ})).values.size == 9000
