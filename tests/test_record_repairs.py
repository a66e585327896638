"""A real logger's record is not always whole: a reading lost and written as NaN (LabVIEW's
"NaN", an old Windows C runtime's "1.#QNAN" or "-1.#IND"), a connection lost for seconds,
the gyro's table knocked and its output saturated.  Before, one NaN refused the whole
record and a knock read as a unit "no gyro's at rest"; now short losses are mended, long
ones and knocks cut out, and each is said.  Records from the independent generator of
``tests.noise_sources``; the simulator's presets only to show nothing is found in them."""

from __future__ import annotations

import io
import math
from dataclasses import replace

import numpy as np
import pytest

from app.core.allan import analyse_record
from app.core.exceptions import UserError
from app.core.record_blocks import reading
from app.core.record_repairs import disturbances, mend_lost_readings
from app.core.static_record import read_static_record
from app.core.text_files import text_lines
from tests.noise_sources import static_record

RATE_HZ, ARW = 10.0, 0.01


def record_text(rates: np.ndarray, cells: dict[int, str] | None = None) -> bytes:
    """A logger's CSV of ``rates`` at 10 Hz, some readings written as ``cells`` says."""
    cells = cells or {}
    lines = ["time_s,value"]
    lines += [f"{k / RATE_HZ:.1f},{cells.get(k, f'{v:.5f}')}" for k, v in enumerate(rates)]
    return ("\n".join(lines) + "\n").encode()


def analysed(text: bytes):
    record = read_static_record(text_lines(text), finite=False)
    return analyse_record(record, None)


def keys(result) -> list[str]:
    return [note["key"] for note in result.notes]


@pytest.mark.parametrize(
    ("cell", "expected"),
    [
        ("NaN", math.nan),
        ("1.#QNAN", math.nan),
        ("-1.#IND", math.nan),
        ("1.#IND00", math.nan),
        ("-nan(ind)", math.nan),
        ("1.#INF", math.inf),
        ("-1.#INF", -math.inf),
        ("10.0346", 10.0346),
    ],
)
def test_a_c_runtimes_spellings_of_nan_and_infinity_are_read(cell, expected):
    value = reading(cell)
    assert (math.isnan(value) and math.isnan(expected)) or value == expected
    with pytest.raises(ValueError):
        reading("1.#Q")


def test_lost_readings_are_mended_and_said_and_the_analysis_is_the_whole_records():
    rates = static_record(1.0, RATE_HZ, arw=ARW, seed=3)
    lost = {17: "NaN", 5000: "1.#QNAN", 12_345: "-1.#IND", 20_000: "nan", 20_001: "nan"}
    whole, mended = analysed(record_text(rates)), analysed(record_text(rates, lost))
    assert "allan.note_lost_mended" in keys(mended)
    note = next(n for n in mended.notes if n["key"] == "allan.note_lost_mended")
    assert note["params"] == {"n": 5, "first_s": 1.7}
    assert mended.samples == whole.samples == rates.size
    assert mended.arw_deg_rt_h == pytest.approx(whole.arw_deg_rt_h, rel=0.002)
    assert mended.arw_deg_rt_h == pytest.approx(ARW, rel=0.05)


def test_a_long_loss_is_a_gap_and_the_longest_stretch_is_analysed():
    rates = static_record(1.0, RATE_HZ, arw=ARW, seed=4)
    lost = {k: "NaN" for k in range(9_000, 9_050)}  # five seconds: a connection lost
    result = analysed(record_text(rates, lost))
    gaps = next(n for n in result.notes if n["key"] == "allan.note_gaps")
    assert gaps["params"]["gaps"] == 1 and gaps["params"]["missing"] == 50
    assert result.samples == rates.size - 9_050
    with pytest.raises(UserError) as refused:
        mend_lost_readings(np.array([np.nan, 1.0, np.nan, np.nan]))
    assert refused.value.key == "readings.not_finite"


def test_a_lab_positions_logger_file_leaves_its_lost_readings_out_and_says_so():
    """One position recorded by a logger, uploaded in the lab: its mean needs no unbroken
    timeline, so a lost reading is left out (not mended) and said; one left alone is
    refused as before, and so is a record made of nothing else."""
    from app.core.one_position_records import parse_one_position_record
    from app.web.i18n import translate

    text = "time_s,value\n0,10.1\n1,NaN\n2,10.2\n3,1.#QNAN\n4,10.0\n"
    parsed = parse_one_position_record(text, "deg/h")
    assert parsed.readings.positions[0].tolist() == [10.1, 10.2, 10.0]
    assert parsed.readings.times_s[0].tolist() == [0.0, 2.0, 4.0]
    assert parsed.notes == ({"key": "allan.note_lost_left_out", "params": {"n": 2, "first": 2}},)
    for language in ("en", "zh-CN"):
        said = translate("allan.note_lost_left_out", language, n=2, first=2)
        assert "2" in said and "{" not in said
    with pytest.raises(UserError) as refused:
        parse_one_position_record("time_s,value\n0,NaN\n1,NaN\n", "deg/h")
    assert refused.value.key == "readings.not_finite"
    with pytest.raises(UserError) as refused:  # a reader called as the API's callers do
        read_static_record(text_lines(b"time_s,value\n0,10.1\n1,NaN\n2,10.2\n"))
    assert refused.value.key == "readings.not_finite"


@pytest.mark.parametrize("knock", ["saturated", "shaken"])
def test_a_knock_is_cut_out_and_said_not_taken_for_a_unit(knock):
    """Ten seconds a third of the way into an hour's record: the output stuck at its
    300 °/s limit, or thrown about by a shaken table.  Before, the curve's floor read
    5.9e3 °/h and the record was refused as in the wrong unit."""
    rates = static_record(1.0, RATE_HZ, arw=ARW, seed=5)
    burst = slice(12_000, 12_100)
    if knock == "saturated":
        rates[burst] = 300.0 * 3600.0
    else:
        rates[burst] += np.random.default_rng(0).normal(0.0, 5000.0, 100)
    result = analysed(record_text(rates))
    note = next(n for n in result.notes if n["key"] == "allan.note_disturbances")
    assert note["params"]["n"] == 1 and 10.0 <= note["params"]["seconds"] <= 11.0
    assert note["params"]["first_s"] == pytest.approx(1200.0, abs=1.0)
    assert result.samples == note["params"]["kept"] == rates.size - 12_104
    assert "allan.note_unit_doubt" not in keys(result)
    assert result.arw_deg_rt_h == pytest.approx(ARW, rel=0.05)


def test_the_notes_are_said_in_both_languages():
    from app.core.allan_summary import note_lines
    from app.web.i18n import translator

    notes = [
        {"key": "allan.note_lost_mended", "params": {"n": 5, "first_s": 1.7}},
        {
            "key": "allan.note_disturbances",
            "params": {"n": 1, "seconds": 10.8, "first_s": 1200.0, "kept": 23896, "kept_s": 2390},
        },
    ]
    for language in ("en", "zh-CN"):
        lines = note_lines(notes, translator(language))
        assert len(lines) == 2 and all("{" not in line for line in lines)
        assert "1.7" in lines[0] and "10.8" in lines[1] and "23896" in lines[1]


def test_no_disturbance_in_records_that_have_none():
    """Independent records of every kind a bench gyro gives -- white, flicker, a strong
    random walk, quantised, a warm-up of 10 °/h over τ = 5 min, a swing, a ramp -- and the
    simulator's presets from switch-on: no run is taken for a knock."""
    from app.core.gyro_stream import GyroStream
    from app.core.presets import PRESETS

    for seed in range(3):
        for hours, rate in ((8.0, 1.0), (1.0, 10.0), (24.0, 0.1)):
            t = np.arange(int(round(hours * 3600 * rate))) / rate
            base = static_record(hours, rate, arw=0.001, flicker=0.005, seed=seed)
            for extra in (
                0.0,
                10.0 * np.exp(-t / 300.0),
                0.5 * np.sin(2 * np.pi * t / 300.0),
                0.3 * np.sign(np.sin(2 * np.pi * t / 1200.0)),
                t / 3600.0,
            ):
                assert not disturbances(base + extra, rate)[0].size, (seed, hours)
        walk = static_record(8.0, 1.0, arw=0.001, rrw=0.5, seed=seed)
        fine = static_record(2.0, 10.0, arw=0.005, lsb_deg=1e-6 / 3.6, seed=seed)
        assert not disturbances(walk, 1.0)[0].size and not disturbances(fine, 10.0)[0].size
    for name, preset in PRESETS.items():
        gyro = replace(preset, turn_on_bias_sigma_deg_h=0.0)
        rates = GyroStream(gyro, 1).read(np.full(int(4 * 3600 * gyro.sample_rate_hz), 10.0))
        assert not disturbances(rates, gyro.sample_rate_hz)[0].size, name


def test_a_teacher_uploads_a_record_with_lost_readings_and_a_knock():
    from app.courses.characterisation import characterise

    rates = static_record(1.0, RATE_HZ, arw=ARW, seed=6)
    rates[20_000:20_050] = 1.0e6
    text = record_text(rates, {100: "NaN", 7_000: "1.#QNAN"})
    # the logger's temperature column, lost at the same moments
    rows = text.decode().splitlines()
    rows = [rows[0] + ",temperature_c"] + [
        row + (",1.#QNAN" if k in (100, 7_000) else ",25.0") for k, row in enumerate(rows[1:])
    ]
    text = ("\n".join(rows) + "\n").encode()
    summary = characterise(io.BytesIO(text), None, None, None)
    said = [note["key"] for note in summary["notes"]]
    assert "allan.note_lost_mended" in said and "allan.note_disturbances" in said
    assert summary["arw_deg_rt_h"] == pytest.approx(ARW, rel=0.05)


def test_what_is_said_is_at_the_records_own_times():
    """A knock at 800 s, so the stretch after it is analysed, and a reading lost at 2000 s:
    said at 2000 s of the record as uploaded, not 1195 s into the stretch kept."""
    rates = static_record(1.0, RATE_HZ, arw=ARW, seed=7)
    rates[8_000:8_050] = 1.0e6
    result = analysed(record_text(rates, {20_000: "NaN"}))
    said = {note["key"]: note["params"] for note in result.notes}
    assert said["allan.note_disturbances"]["first_s"] == pytest.approx(800.0, abs=0.5)
    assert said["allan.note_lost_mended"]["first_s"] == 2000.0
