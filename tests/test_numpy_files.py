"""A static gyro record saved by NumPy -- ``np.save`` of the readings, of rows of
``time_s, value`` or ``time_s, value, temperature_c`` (the REST API's layouts), or
``np.savez`` of named arrays (``omega`` beside ``fs``, ``t``, an IMU's matrix) -- read for
the teacher's characterisation and ``gyrolab allan``, each said; an object array never
unpickled, another shape or a damaged file refused in words."""

from __future__ import annotations

import io

import numpy as np
import pytest

from app.core.allan import analyse_record
from app.core.exceptions import UserError
from app.core.numpy_files import is_npy, is_npz, numpy_record
from app.core.record_columns import ColumnChoiceNeeded
from app.web.i18n import translator
from tests.noise_sources import static_record
from tests.test_binary_uploads import npy_claiming
from tests.test_characterisation import shown, stored, upload
from tests.test_characterisation import world as world  # noqa: F401 -- the fixture

ARW = 0.02  # °/√h
RATE_HZ = 20.0


def gyro(hours: float = 0.5) -> np.ndarray:
    return static_record(hours, RATE_HZ, arw=ARW, seed=9, bias=2.0)


def saved(array, allow_pickle: bool = False) -> bytes:
    out = io.BytesIO()
    np.save(out, array, allow_pickle=allow_pickle)
    return out.getvalue()


def archived(compressed: bool = True, **arrays) -> bytes:
    out = io.BytesIO()
    (np.savez_compressed if compressed else np.savez)(out, **arrays)
    return out.getvalue()


def notes(result) -> dict:
    return {note["key"]: note["params"] for note in result.notes}


def test_the_readings_alone_or_with_their_times_and_temperatures():
    rates = gyro()
    times = np.arange(rates.size) / RATE_HZ
    alone = numpy_record(saved(rates))
    assert alone.values == pytest.approx(rates) and alone.times_s is None
    result = analyse_record(alone, RATE_HZ)
    assert result.arw_deg_rt_h == pytest.approx(ARW, rel=0.05)
    assert "allan.note_npy" in notes(result)
    timed = numpy_record(saved(np.column_stack([times, rates])))
    assert timed.times_s == pytest.approx(times)
    assert analyse_record(timed, None).arw_deg_rt_h == pytest.approx(ARW, rel=0.05)
    warm = numpy_record(saved(np.column_stack([times, rates, np.full(rates.size, 31.5)])))
    assert warm.temperatures_c == pytest.approx(np.full(rates.size, 31.5))
    assert translator("zh-CN")("allan.note_npy_temperatures") == (
        "按 NumPy 数组文件（.npy）读取：每行为 time_s、读数、壳体温度（°C）。"
    )


def test_an_archive_of_named_arrays_is_read_as_matlabs_variables_are():
    rates = gyro()
    data = archived(omega=rates, fs=RATE_HZ, label=np.array("bench 3"))
    assert is_npz(data) and not is_npy(data[:20]) and not is_npz(b"PK\x03\x04 not a zip")
    result = analyse_record(numpy_record(data), None)
    assert result.rate_hz == RATE_HZ
    assert result.arw_deg_rt_h == pytest.approx(ARW, rel=0.05)
    said = notes(result)
    assert translator("en")("allan.note_numpy", **said["allan.note_numpy"]) == (
        "Read as a NumPy archive (.npz): the readings are its array omega."
    )
    assert said["allan.note_array_rate"] == {"name": "fs", "rate": "20"}
    axes = archived(gyro=np.column_stack([rates, rates + 1.0]), t=np.arange(rates.size) / 20)
    with pytest.raises(ColumnChoiceNeeded) as offered:
        numpy_record(axes)
    assert offered.value.key == "numpy.choose_vector"
    assert offered.value.choices == ["gyro 1", "gyro 2"]
    chosen = numpy_record(axes, "gyro 2")
    assert chosen.values == pytest.approx(rates + 1.0) and chosen.times_s[1] == 0.05


@pytest.mark.parametrize(
    ("data", "key"),
    [
        (saved(np.array([{"run": 1}] * 20, dtype=object), allow_pickle=True), "numpy.unreadable"),
        (saved(np.zeros((4, 4, 4))), "numpy.shape"),
        (saved(np.zeros((100, 5))), "numpy.shape"),
        (saved(np.arange(5000.0))[:300], "numpy.unreadable"),
        (saved(np.array(["a", "b"] * 20)), "numpy.unreadable"),
        (archived(name=np.array("bench"), fs=np.array(10.0)), "numpy.no_record"),
        # a header claiming 10¹² numbers over 64 bytes: np.load set them aside first
        (npy_claiming((10**12,)), "numpy.unreadable"),
        (npy_claiming((-5,)), "numpy.unreadable"),
    ],
)
def test_what_cannot_be_read_is_said_in_both_languages_and_nothing_is_unpickled(data, key):
    with pytest.raises(UserError) as refused:
        numpy_record(data)
    assert refused.value.key == key
    for language in ("en", "zh-CN"):
        words = translator(language)(key, **refused.value.params)
        assert words and not words.startswith("numpy.")


def test_an_archive_past_the_limit_is_refused_before_it_is_unpacked(monkeypatch):
    from app.core import numpy_files

    monkeypatch.setattr(numpy_files, "MAX_ELEMENTS", 1000)
    with pytest.raises(UserError) as refused:
        numpy_record(archived(w=np.zeros(200_000)))  # 1.6 MB unpacked, a few kB packed
    assert refused.value.key == "numpy.too_large"


@pytest.mark.one_backend  # the file's reading; storing a characterisation is tested on both
def test_the_teacher_characterises_the_bench_from_an_npz_archive(world):  # noqa: F811
    from tests.factories import browser

    teacher = browser(world, "teacher1")
    rates = gyro(0.5)
    reply = upload(teacher, world, archived(omega=rates, fs=RATE_HZ), rate="")
    assert reply.status_code == 303, reply.text
    assert stored(world)["arw_deg_rt_h"] == pytest.approx(ARW, rel=0.05)
    assert "the readings are its array omega" in shown(teacher, reply)
