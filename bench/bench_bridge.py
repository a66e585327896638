"""How fast the bridge parses real instrument streams, on one core.

    .venv/bin/python bench/bench_bridge.py [--seconds 60]

Builds a stream of each format as the gyro would send it (KVH DSP-1750 format A at
1000 Hz with 0.1 % of frames corrupted and 0.1 % lost; KVH DSP-3000 lines; a teaching
FOG's 10-byte frame), feeds it in 4096-byte reads through the decoder and the sample
maker (frames → °/h with the gyro's own times), and prints frames parsed per second
against a bare baseline measured in the same run: ``struct.unpack_from`` of every
frame at known offsets (no search, no check, no conversion), the least any Python
parser of this format does.  The goal is ≥ 10× the DSP-1750's 1000 Hz.
"""

from __future__ import annotations

import argparse
import os
import platform
import struct
import time

import numpy as np

from app.bridge.checksums import CHECKSUMS
from app.bridge.instruments import Instrument, set_up
from app.bridge.samples import SampleMaker

READ_BYTES = 4096
GOAL_FRAMES_PER_S = 10 * 1000


def dsp1750_stream(count: int, rng: np.random.Generator) -> bytes:
    crc = CHECKSUMS["crc32-mpeg2"].compute
    frames = []
    for index in range(count):
        body = (
            b"\xfe\x81\xff\x55"
            + struct.pack(">6f", 0.0, 0.0, float(rng.normal(7e-8, 1e-8)), 0.0, 0.0, 1.0)
            + bytes([0x74, index % 128])
            + struct.pack(">h", 31)
        )
        frame = bytearray(body + struct.pack(">I", crc(body)))
        if rng.random() < 0.001:
            frame[9] ^= 0xFF  # corrupted on the line
        if rng.random() < 0.001:
            continue  # lost
        frames.append(bytes(frame))
    return b"".join(frames)


def dsp3000_stream(count: int, rng: np.random.Generator) -> bytes:
    return "".join(f"{v:.6f} 1\r\n" for v in rng.normal(0.0042, 0.001, count)).encode()


def teaching_stream(count: int, rng: np.random.Generator) -> bytes:
    frames = []
    for index in range(count):
        body = struct.pack("<2sihB", b"\x99\x66", int(rng.normal(150000, 50)), 2450, index % 256)
        frames.append(body + bytes([sum(body[2:]) % 256]))
    return b"".join(frames)


def parse_rate(instrument: Instrument, data: bytes, mid_line: bool = False) -> tuple[float, int]:
    """(frames per second, samples made) through decoder and sample maker, best of 3."""
    best = float("inf")
    made = 0
    for _ in range(3):
        setup = set_up(instrument, mid_line=mid_line)
        maker = SampleMaker(setup.unit, setup.rate_hz)
        made = 0
        start = time.perf_counter()
        for at in range(0, len(data), READ_BYTES):
            made += len(maker.make(setup.decoder.feed(data[at : at + READ_BYTES])))
        best = min(best, time.perf_counter() - start)
    frames = setup.decoder.stats.frames
    return frames / best, made


def bare_rate(data: bytes, frame_bytes: int, layout: str) -> float:
    """The baseline: unpack every frame at its known offset, nothing else."""
    unpack = struct.Struct(layout).unpack_from
    count = len(data) // frame_bytes
    best = float("inf")
    for _ in range(3):
        start = time.perf_counter()
        for offset in range(0, count * frame_bytes, frame_bytes):
            unpack(data, offset)
        best = min(best, time.perf_counter() - start)
    return count / best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="of DSP-1750 output")
    args = parser.parse_args()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})  # one core
    rng = np.random.default_rng(0)
    count = int(args.seconds * 1000)
    kvh = dsp1750_stream(count, rng)
    bare = bare_rate(kvh, 36, ">4s6fBBhI")
    rows = [
        ("baseline: struct.unpack_from at known offsets (DSP-1750)", bare, None),
        ("kvh-dsp1750: search, CRC-32, counter, Δθ → °/h, times",)
        + parse_rate(Instrument("kvh-dsp1750"), kvh),
        ("kvh-dsp3000: lines, validity, °/s → °/h, times",)
        + parse_rate(Instrument("kvh-dsp3000"), dsp3000_stream(count, rng)),
        ("frame: 99 66 teaching FOG, sum8, counter, temperature",)
        + parse_rate(
            Instrument(
                "frame:hdr=9966, z:<i4*0.0001, temp:<i2*0.01, seq:u1, check=sum8@2, "
                "rate=200, unit=deg/h"
            ),
            teaching_stream(count, rng),
        ),
    ]
    print(
        f"machine: {platform.machine()}, Python {platform.python_version()}, one core; "
        f"{count} frames per format ({args.seconds:.0f} s of a DSP-1750 at 1000 Hz)"
    )
    print(f"{'':60s} {'frames/s':>10s} {'× bare':>7s} {'× 1000 Hz':>9s}")
    for name, rate, _ in rows:
        print(f"{name:60s} {rate:10.0f} {rate / bare:7.3f} {rate / 1000:9.1f}")
    kvh_rate = rows[1][1]
    verdict = "met" if kvh_rate >= GOAL_FRAMES_PER_S else "NOT met"
    print(f"goal ≥ {GOAL_FRAMES_PER_S} DSP-1750 frames/s on one core: {verdict}")


if __name__ == "__main__":
    main()
