"""Byte streams as real gyros send them, built here from the data-sheet layouts with code
of the tests' own (bit-by-bit CRCs from their definitions, ``struct`` packing), never with
the bridge's decoder or its checksum library — so that a round trip tests both sides.

* KVH DSP-1750/1760 format A: FE 81 FF 55, six big-endian float32 (gyro X Y Z, accel
  X Y Z), status, counter 0–127, big-endian int16 temperature, CRC-32/MPEG-2 of bytes 0–31;
* KVH DSP-3000: ASCII ``(-)xxx.xxxxxx y`` lines;
* a teaching FOG's short frame: 99 66, little-endian int32 rate (1e-4 °/h), little-endian
  int16 temperature (0.01 °C), counter, sum8 from byte 2.
"""

from __future__ import annotations

import functools
import math
import operator
import struct

import numpy as np

KVH_HEADER = bytes.fromhex("FE81FF55")
# the KVH manual's sample output of format A (all sensors valid, counter 0x3D, 40 °C)
KVH_MANUAL_EXAMPLE = bytes.fromhex(
    "FE81FF55 37A96A6E 38586C1F B75BF862 BF803E78 BB650D28 3B0A37AC 77 3D 0028 4BFA34D8"
)
TEACHING_SPEC = "hdr=99 66, z:<i4*0.0001, temp:<i2*0.01, seq:u1, check=sum8@2, rate=200, unit=deg/h"
RAD_PER_DEG = math.pi / 180


def crc_msb_first(data: bytes, width: int, polynomial: int, initial: int) -> int:
    """A CRC bit by bit from its definition: MSB first, no reflection, no final XOR."""
    top, mask = 1 << (width - 1), (1 << width) - 1
    crc = initial
    for byte in data:
        crc ^= byte << (width - 8)
        for _ in range(8):
            crc = ((crc << 1) ^ polynomial) if crc & top else crc << 1
            crc &= mask
    return crc


def crc32_mpeg2(data: bytes) -> int:
    """CRC-32/MPEG-2: poly 0x04C11DB7, init 0xFFFFFFFF."""
    return crc_msb_first(data, 32, 0x04C11DB7, 0xFFFFFFFF)


def crc16_ccitt(data: bytes) -> int:
    """CRC-16/CCITT-FALSE: poly 0x1021, init 0xFFFF."""
    return crc_msb_first(data, 16, 0x1021, 0xFFFF)


def dsp1750_frame(
    gyro: tuple[float, float, float],
    counter: int,
    *,
    status: int = 0x77,
    temperature: int = 25,
    accel: tuple[float, float, float] = (0.0, 0.0, 1.0),
) -> bytes:
    body = (
        KVH_HEADER
        + struct.pack(">6f", *gyro, *accel)
        + bytes([status, counter % 128])
        + struct.pack(">h", temperature)
    )
    return body + struct.pack(">I", crc32_mpeg2(body))


def dsp1750_stream(
    rates_deg_h: np.ndarray, *, rate_hz: float = 1000.0, axis: int = 2, first_counter: int = 0
) -> list[bytes]:
    """One frame per rate: the rate as a Δangle in radians over 1/rate_hz on ``axis``, the
    only gyro flagged valid (a one-axis DSP-1750), the other axes' words left at noise."""
    frames = []
    for index, rate in enumerate(rates_deg_h):
        delta_rad = rate / 3600.0 / rate_hz * RAD_PER_DEG
        gyro = [1e-7, -2e-7, 3e-7]
        gyro[axis] = delta_rad
        status = 0x70 | (1 << axis)
        frames.append(
            dsp1750_frame(tuple(gyro), first_counter + index, status=status, temperature=30)
        )
    return frames


def dsp3000_lines(values: np.ndarray, faults: set[int] = frozenset()) -> list[bytes]:
    return [f"{v:.6f} {0 if i in faults else 1}\r\n".encode() for i, v in enumerate(values)]


def vectornav_lines(
    rates_deg_h: np.ndarray,
    *,
    kind: str = "VNYMR",
    axis: int = 2,
    crc: bool = False,
    temperature_c: float = 24.5,
) -> list[bytes]:
    """A VN-100's ASCII sentences, one per rate: the rate in rad/s to six decimals on
    ``axis`` (the others small), checked by the 8-bit XOR or the 16-bit CRC (CRC-16/XMODEM:
    poly 0x1021, init 0, as VectorNav's manual computes it)."""
    lines = []
    for rate in rates_deg_h:
        gyro = ["+00.000010", "-00.000020", "+00.000030"]
        gyro[axis] = f"{rate / 3600.0 * RAD_PER_DEG:+010.6f}"
        fields = ["+00.1234", "-00.5678", "+00.1234", "-00.012", "+00.034", "-09.801", *gyro]
        if kind == "VNYMR":
            fields = ["+010.123", "-001.234", "+000.567", *fields]
        else:  # VNIMU: the temperature and the pressure after the rates
            fields += [f"{temperature_c:+05.1f}", "+084.322"]
        body = ",".join([kind, *fields]).encode()
        if crc:
            check = f"{crc_msb_first(body, 16, 0x1021, 0x0000):04X}"
        else:
            check = f"{functools.reduce(operator.xor, body, 0):02X}"
        lines.append(b"$" + body + b"*" + check.encode() + b"\r\n")
    return lines


def teaching_frame(rate_deg_h: float, counter: int, temperature_c: float = 24.5) -> bytes:
    body = (
        b"\x99\x66"
        + struct.pack("<i", round(rate_deg_h / 1e-4))
        + struct.pack("<h", round(temperature_c / 0.01))
        + bytes([counter % 256])
    )
    return body + bytes([sum(body[2:]) % 256])


def chunked(data: bytes, seed: int = 0, largest: int = 97) -> list[bytes]:
    """The stream cut into random pieces (a serial read returns whatever has arrived)."""
    rng = np.random.default_rng(seed)
    pieces, at = [], 0
    while at < len(data):
        size = int(rng.integers(1, largest + 1))
        pieces.append(data[at : at + size])
        at += size
    return pieces
