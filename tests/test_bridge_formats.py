"""The bridge's instrument formats, from bytes made by the tests' own encoder
(tests/instrument_streams.py) to samples: KVH DSP-1750 format A, KVH DSP-3000 lines,
described frames, checksums, resynchronisation, lost and wrapped counters, bounds."""

from __future__ import annotations

import math
import struct

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from app.bridge.checksums import CHECKSUMS
from app.bridge.frames import FrameDecoder, parse_spec
from app.bridge.instruments import KVH_DSP1750, Instrument, set_up
from app.bridge.samples import SampleMaker
from app.core.exceptions import UserError
from app.core.record_checks import record_gaps
from tests.instrument_streams import (
    KVH_MANUAL_EXAMPLE,
    TEACHING_SPEC,
    chunked,
    crc16_ccitt,
    crc32_mpeg2,
    dsp1750_frame,
    dsp1750_stream,
    dsp3000_lines,
    teaching_frame,
    vectornav_lines,
)

RATES = 15.0 + 0.5 * np.sin(np.arange(600) / 40.0)  # °/h, a gyro at rest plus a slow wave


def decode(
    instrument: Instrument, data: bytes, *, seed: int = 0, start_s: float = 0.0, mid_line=False
):
    """Every sample of ``data`` fed in random pieces; (samples, decoder stats, maker)."""
    setup = set_up(instrument, mid_line=mid_line)
    maker = SampleMaker(
        setup.unit, setup.rate_hz, integrated=instrument.integrated, start_s=start_s
    )
    samples = []
    for piece in chunked(data, seed):
        samples += maker.make(setup.decoder.feed(piece))
    return samples, setup.decoder.stats, maker


def values(samples) -> np.ndarray:
    return np.array([s.rate_deg_h for s in samples])


def times(samples) -> np.ndarray:
    return np.array([s.time_s for s in samples])


def test_checksums_match_the_catalogue_and_the_kvh_manual():
    check = b"123456789"  # the CRC catalogue's check input
    assert CHECKSUMS["crc32-mpeg2"].compute(check) == 0x0376E6E7 == crc32_mpeg2(check)
    assert CHECKSUMS["crc16-ccitt"].compute(check) == 0x29B1 == crc16_ccitt(check)
    assert CHECKSUMS["sum8"].compute(check) == sum(check) % 256 == 0xDD
    assert CHECKSUMS["xor8"].compute(check) == 0x31
    example = KVH_MANUAL_EXAMPLE  # the manual's sample output ends in its CRC 0x4BFA34D8
    assert CHECKSUMS["crc32-mpeg2"].compute(example[:32]) == 0x4BFA34D8
    assert example[32:] == bytes.fromhex("4BFA34D8")


def test_the_kvh_manual_example_decodes():
    decoder = FrameDecoder(KVH_DSP1750)
    (frame,) = decoder.feed(KVH_MANUAL_EXAMPLE)
    gyro_x = struct.unpack(">f", bytes.fromhex("37A96A6E"))[0]
    assert frame.value == gyro_x and frame.temperature_c == 40.0
    assert decoder.axis == "x"  # status 0x77: every gyro valid, the first one is used
    z = FrameDecoder(KVH_DSP1750, "z").feed(KVH_MANUAL_EXAMPLE)[0]
    assert z.value == struct.unpack(">f", bytes.fromhex("B75BF862"))[0]


def test_dsp1750_delta_angles_round_trip_to_rates_and_times():
    data = b"".join(dsp1750_stream(RATES, axis=2))
    samples, stats, maker = decode(Instrument("kvh-dsp1750"), data, start_s=3600.0)
    # Δθ [rad] over 1 ms → °/h; float32 keeps about 7 digits
    assert values(samples) == pytest.approx(RATES, rel=1e-6)
    assert times(samples) == pytest.approx(3600.0 + np.arange(RATES.size) / 1000.0)
    assert {s.temperature_c for s in samples} == {30.0}
    assert stats.frames == RATES.size and stats.missing == stats.corrupt == 0
    assert maker.absent == 0  # 600 frames: the counter wrapped 127 → 0 four times


def test_dsp1750_rates_in_degrees_per_second_and_another_rate():
    frames = [
        dsp1750_frame((0.0, 0.0, r / 3600.0), i, status=0x74) for i, r in enumerate(RATES[:50])
    ]
    samples, _, _ = decode(Instrument("kvh-dsp1750", unit="deg/s", rate_hz=250.0), b"".join(frames))
    assert values(samples) == pytest.approx(RATES[:50], rel=1e-6)
    assert times(samples)[1] == pytest.approx(1 / 250.0)


def test_garbage_partial_frames_and_corrupted_bytes_are_survived_and_counted():
    frames = dsp1750_stream(RATES[:300])
    corrupted = {40, 41, 200}
    for index in corrupted:
        damaged = bytearray(frames[index])
        damaged[10] ^= 0x5A  # a flipped byte inside the rotation word
        frames[index] = bytes(damaged)
    data = (
        frames[0][17:]  # the port opened mid-frame
        + b"".join(frames[1:100])
        + b"\xfe\x81\x00noise\xfe\x81\xff"  # line noise, even a broken header
        + b"".join(frames[100:])
    )
    samples, stats, maker = decode(Instrument("kvh-dsp1750"), data, seed=4)
    kept = [i for i in range(1, 300) if i not in corrupted]
    assert values(samples) == pytest.approx(RATES[kept], rel=1e-6)
    assert stats.corrupt == 2  # 40 and 41 follow each other: one loss of lock
    assert stats.missing == 3  # the counter shows every dropped frame
    assert maker.gaps == 2 and maker.absent == 3
    assert stats.garbage_bytes > 0 and stats.resyncs >= 2
    gap = np.diff(times(samples))
    assert gap.max() == pytest.approx(0.003)  # 40 and 41 missing: 39 → 42


def test_dropped_frames_show_as_gaps_even_across_a_counter_wrap():
    frames = dsp1750_stream(RATES[:400])
    dropped = {127, 128, 300}  # counter 127, then 0 (its wrap), and one more
    data = b"".join(f for i, f in enumerate(frames) if i not in dropped)
    samples, stats, maker = decode(Instrument("kvh-dsp1750"), data)
    assert len(samples) == 397 and stats.missing == 3 and stats.corrupt == 0
    assert maker.gaps == 2 and maker.absent == 3
    stamps = times(samples)
    assert stamps[126] == pytest.approx(0.126) and stamps[127] == pytest.approx(0.129)


def test_fault_frames_are_dropped_and_the_chosen_axis_is_respected():
    frames = dsp1750_stream(RATES[:20], axis=2)
    invalid = bytearray(frames[5])
    invalid[28] = 0x70  # gyro Z flagged invalid
    body = bytes(invalid[:32])
    frames[5] = body + struct.pack(">I", crc32_mpeg2(body))
    samples, stats, maker = decode(Instrument("kvh-dsp1750"), b"".join(frames))
    assert len(samples) == 19 and stats.faults == 1 and maker.absent == 1
    # asking for X, whose status bit is clear in every frame: nothing is valid
    samples, stats, _ = decode(Instrument("kvh-dsp1750", axis="x"), b"".join(frames))
    assert samples == [] and stats.faults == 20


def test_repeated_counters_are_dropped_not_joined():
    frames = dsp1750_stream(RATES[:10])
    data = b"".join(frames[:5] + [frames[4]] + frames[5:])
    samples, stats, _ = decode(Instrument("kvh-dsp1750"), data)
    assert len(samples) == 10 and stats.repeated == 1


def test_dsp3000_lines_rate_incremental_and_integrated():
    rates_deg_s = RATES[:200] / 3600.0
    text = b"".join(dsp3000_lines(rates_deg_s, faults={7}))
    # the port opened mid-line: "3 1" is the end of a line, not a reading
    samples, stats, maker = decode(Instrument("kvh-dsp3000"), b"3 1\r\n" + text, mid_line=True)
    assert values(samples) == pytest.approx(np.delete(RATES[:200], 7), abs=0.0036 / 2)
    assert stats.faults == 1 and maker.absent == 1 and times(samples)[7] == pytest.approx(0.08)
    angles_deg = RATES[:200] / 3600.0 / 100.0
    samples, _, _ = decode(
        Instrument("kvh-dsp3000", unit="deg"), b"".join(dsp3000_lines(angles_deg))
    )
    assert values(samples)[50] == pytest.approx(RATES[50], abs=0.36)  # 1e-6° resolution
    total = np.cumsum(RATES[:200] / 3600.0 / 100.0) + 123.0
    samples, _, _ = decode(
        Instrument("kvh-dsp3000", unit="deg", integrated=True),
        b"".join(dsp3000_lines(total)),
    )
    assert len(samples) == 199
    assert np.mean(values(samples)) == pytest.approx(np.mean(RATES[1:200]), abs=0.05)


def test_dsp3000_garbled_and_overlong_lines_are_dropped_with_bounded_memory():
    lines = dsp3000_lines(RATES[:30] / 3600.0)
    lines[10] = b"0.00\x8f\x12 1\r\n"  # corrupted on the line
    data = b"".join(lines[:20]) + b"\x00" * 10_000 + b"\n" + b"".join(lines[20:])
    setup = set_up(Instrument("kvh-dsp3000"), mid_line=False)
    maker = SampleMaker(setup.unit, setup.rate_hz)
    samples = []
    for piece in chunked(data, 2, largest=512):
        samples += maker.make(setup.decoder.feed(piece))
        assert len(setup.decoder._splitter._partial) <= 64
    assert len(samples) == 29 and setup.decoder.stats.corrupt == 1
    assert setup.decoder.stats.garbage_bytes >= 10_000


def test_vectornav_sentences_checksums_other_outputs_and_the_axis():
    """$VNYMR with 8-bit checksums, the port opened mid-sentence: the z axis's rate, to
    the sentence's six decimals of rad/s (0.21 °/h); a sentence whose checksum fails is a
    one-period gap; a reply to a command ($VNRRG) is no period."""
    lines = vectornav_lines(RATES[:200])
    lines[30] = lines[30].replace(b"+00.1234", b"+00.1334", 1)  # a bit flipped on the wire
    lines.insert(100, b"$VNRRG,07,40*59\r\n")
    data = b"$VNYMR,+0.000" + b"\r\n" + b"".join(lines)
    samples, stats, maker = decode(Instrument("vectornav"), data, mid_line=True)
    assert values(samples) == pytest.approx(np.delete(RATES[:200], 30), abs=0.21 / 2)
    assert stats.corrupt == 1 and maker.absent == 1
    assert times(samples)[30] == pytest.approx(31 / 40.0)  # 40 Hz, the gap kept
    imu = vectornav_lines(RATES[:50], kind="VNIMU", axis=0, crc=True, temperature_c=31.5)
    samples, stats, _ = decode(Instrument("vectornav", axis="x"), b"".join(imu))
    assert len(samples) == 50 and stats.corrupt == 0
    assert values(samples) == pytest.approx(RATES[:50], abs=0.21 / 2)
    assert {s.temperature_c for s in samples} == {31.5}
    samples, _, _ = decode(Instrument("vectornav"), b"".join(imu))  # z: the small one
    assert abs(np.mean(values(samples))) < 10.0
    assert Instrument("vectornav").default_baud() == 115200


def test_a_described_teaching_frame_round_trips_through_the_mini_language_and_toml(tmp_path):
    frames = [teaching_frame(rate, i, 24.5 + i / 100) for i, rate in enumerate(RATES[:300])]
    frames[77] = frames[77][:-1] + bytes([(frames[77][-1] + 1) % 256])  # bad sum
    data = b"\x99\x80\x00" + b"".join(frames)
    for spec in (TEACHING_SPEC, str(toml_file(tmp_path))):
        samples, stats, maker = decode(Instrument("frame:" + spec), data, seed=9)
        kept = np.delete(np.arange(300), 77)
        assert values(samples) == pytest.approx(RATES[kept], abs=1e-4)
        assert times(samples) == pytest.approx(kept / 200.0)
        assert [s.temperature_c for s in samples][:2] == pytest.approx([24.5, 24.51])
        assert stats.corrupt == 1 and stats.missing == 1 and maker.absent == 1


def toml_file(tmp_path):
    path = tmp_path / "teaching-fog.toml"
    path.write_text(
        'header = "99 66"\n'
        'fields = ["z:<i4*0.0001", "temp:<i2*0.01", "seq:u1"]\n'
        'checksum = "sum8"\nchecksum_from = 2\nrate_hz = 200\nunit = "deg/h"\n',
        encoding="utf-8",
    )
    return path


def test_a_one_byte_header_locks_on_only_when_the_next_frame_confirms_it():
    """0x80-headed frames with an xor8 after random line noise: a 1-byte header with a
    1-byte check passes by chance 1 time in 256, so a candidate needs the next header too."""
    spec = "hdr=80, z:>i3*0.001, check=xor8@1, rate=100, unit=deg/h"
    rng = np.random.default_rng(5)
    noise = rng.integers(0, 256, 3000, dtype=np.uint8).tobytes()

    def frame(rate: float) -> bytes:
        body = b"\x80" + round(rate / 0.001).to_bytes(3, "big", signed=True)
        return body + bytes([body[1] ^ body[2] ^ body[3]])

    data = noise + b"".join(frame(r) for r in RATES[:100])
    samples, stats, _ = decode(Instrument("frame:" + spec), data)
    assert values(samples) == pytest.approx(RATES[:100], abs=1e-3)  # none made up from noise
    assert stats.garbage_bytes >= 3000 - 5 * 4


def test_crc16_frames_and_every_field_type():
    spec = parse_spec(
        "hdr=AA55, x:<f8, y:>u2*0.5, z:<i2, temp:u1, status:u1&0x01!0x80, seq:>u2%1000,"
        " check=crc16-ccitt, rate=50, unit=deg/s"
    )
    assert spec.length == 2 + 8 + 2 + 2 + 1 + 1 + 2 + 2

    def frame(index: int, status: int = 0x01) -> bytes:
        body = (
            b"\xaa\x55"
            + struct.pack("<d", 0.25 * index)
            + struct.pack(">H", 7)
            + struct.pack("<h", -3)
            + bytes([20, status])
            + struct.pack(">H", index % 1000)
        )
        return body + struct.pack(">H", crc16_ccitt(body))

    data = b"".join(frame(i, 0x81 if i == 998 else 0x01) for i in range(995, 1010))
    decoder = FrameDecoder(spec)
    decoded = decoder.feed(data)
    assert [f.value for f in decoded][:3] == [0.25 * 995, 0.25 * 996, 0.25 * 997]
    assert decoder.stats.faults == 1 and decoder.stats.missing == 0  # counter wrapped at 1000
    assert FrameDecoder(spec, "y").feed(frame(1))[0].value == 3.5
    assert FrameDecoder(spec, "z").feed(frame(1))[0].value == -3


@pytest.mark.parametrize(
    ("spec", "key"),
    [
        ("z:>i4, unit=deg/h", "bridge.spec_header"),
        ("hdr=zz, z:>i4", "bridge.spec_header"),
        ("hdr=99, z:>i9", "bridge.spec_type"),
        ("hdr=99, z>i4", "bridge.spec_field"),
        ("hdr=99, w:>i4", "bridge.spec_field"),
        ("hdr=99, z:>f2", "bridge.spec_type"),
        ("hdr=99, temp:>i2", "bridge.spec_no_axis"),
        ("hdr=99, z:>i4, z:>i4", "bridge.spec_repeated"),
        ("hdr=99, z:>i4, check=md5", "bridge.spec_checksum"),
        ("hdr=99, z:>i4, check=sum8@9", "bridge.spec_checksum_from"),
        ("hdr=99, z:>i4, unit=furlongs", "bridge.spec_unit"),
        ("hdr=99, z:>i4, rate=-5", "bridge.spec_rate"),
        ("hdr=99, z:>i4, baud=9600", "bridge.spec_setting"),
        ("hdr=99, z:>i4, _:2000", "bridge.spec_too_long"),
        ("nowhere.toml", "bridge.cannot_read"),
    ],
)
def test_bad_descriptions_are_refused_with_a_message(spec, key):
    with pytest.raises(UserError) as caught:
        parse_spec(spec)
    assert caught.value.key == key


def test_instrument_set_up_refuses_what_cannot_work():
    with pytest.raises(UserError, match="format"):
        set_up(Instrument("kvh-dsp9999"))
    with pytest.raises(UserError) as caught:
        set_up(Instrument("frame:hdr=99, z:>i4"))
    assert caught.value.key == "bridge.spec_needs_unit"
    with pytest.raises(UserError) as caught:
        SampleMaker("deg", None)
    assert caught.value.key == "bridge.needs_rate"
    with pytest.raises(UserError) as caught:
        set_up(Instrument("kvh-dsp1750", axis="w"))
    assert caught.value.key == "bridge.no_such_axis"


def test_the_frame_buffer_stays_bounded_under_endless_garbage():
    decoder = FrameDecoder(KVH_DSP1750)
    rng = np.random.default_rng(1)
    for _ in range(200):
        decoder.feed(rng.integers(0, 256, 8192, dtype=np.uint8).tobytes().replace(b"\xfe", b"\x00"))
        assert len(decoder._buffer) <= KVH_DSP1750.length
    assert decoder.stats.garbage_bytes >= 200 * 8192 - KVH_DSP1750.length
    assert decoder.stats.frames == 0


def test_nan_rates_from_a_broken_gyro_are_dropped():
    nan_frame = dsp1750_frame((0.0, 0.0, math.nan), 0, status=0x74)
    good = dsp1750_frame((0.0, 0.0, 1e-6), 1, status=0x74)
    decoder = FrameDecoder(KVH_DSP1750)
    assert len(decoder.feed(nan_frame + good)) == 1 and decoder.stats.faults == 1


def test_record_gaps_counts_missing_readings_not_clock_jitter():
    steps = np.arange(200) * 0.01
    jittered = steps + np.random.default_rng(3).normal(0, 0.001, 200)
    assert record_gaps(jittered) == (0, 0)
    assert record_gaps(np.delete(steps, [10, 11, 50])) == (2, 3)
    assert record_gaps(np.delete(steps, np.arange(100, 150))) == (1, 50)
    assert record_gaps(np.zeros(10)) == (0, 0) and record_gaps(np.array([1.0, 5.0])) == (0, 0)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.binary(max_size=80), max_size=30), st.integers(0, 2**32 - 1))
def test_any_bytes_at_all_never_break_a_decoder(pieces, seed):
    """Line noise, cut frames and lookalike headers: decoders count, they never raise,
    and what they keep from real frames mixed into the noise is exact."""
    frames = dsp1750_stream(RATES[:5])
    rng = np.random.default_rng(seed)
    stream = b"".join(piece + frames[int(rng.integers(0, 5))] for piece in pieces)
    for instrument in (
        Instrument("kvh-dsp1750"),
        Instrument("kvh-dsp3000"),
        Instrument("frame:" + TEACHING_SPEC),
        Instrument("text", column=1),
        Instrument("vectornav"),
    ):
        samples, stats, _ = decode(instrument, stream, seed=seed % 1000)
        assert all(math.isfinite(s.rate_deg_h) for s in samples)
        assert stats.frames == len(samples)
    kvh, _, _ = decode(Instrument("kvh-dsp1750"), stream)
    assert set(np.round(values(kvh), 6)) <= set(np.round(RATES[:5], 6))
