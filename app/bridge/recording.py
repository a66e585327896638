"""A raw recording of what a gyro sent: every chunk of bytes as it arrived, with its time,
so that one real run can be replayed through the same decoder later (by a class, or by
the tests).

File layout: the line ``GYROLAB-RAW 1``, one line of JSON (how the run was read: format,
axis, unit, rate, when it started), then records of ``<d`` seconds since the start,
``<I`` length and that many bytes, each little-endian.
"""

from __future__ import annotations

import json
import math
import struct
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO

from app.bridge.frames import MAX_RATE_HZ
from app.core.exceptions import UserError

MAGIC = b"GYROLAB-RAW 1\n"
RECORD = struct.Struct("<dI")
MAX_CHUNK_BYTES = 1 << 20
MAX_META_BYTES = 64 * 1024


class Recorder:
    """Writes a recording; chunks are flushed at least once a second."""

    def __init__(self, path: Path, meta: dict) -> None:
        try:
            self._file: BinaryIO = path.open("wb")
        except OSError as error:
            raise UserError("bridge.cannot_write", path=str(path), error=error.strerror) from None
        self._file.write(MAGIC)
        self._file.write(json.dumps(meta, ensure_ascii=False).encode() + b"\n")
        self._flushed = time.monotonic()
        self.bytes = 0

    def write(self, seconds: float, chunk: bytes) -> None:
        if not chunk:
            return
        self._file.write(RECORD.pack(seconds, len(chunk)))
        self._file.write(chunk)
        self.bytes += len(chunk)
        now = time.monotonic()
        if now - self._flushed >= 1.0:
            self._file.flush()
            self._flushed = now

    def close(self) -> None:
        self._file.close()


@dataclass
class Recording:
    """An open recording: its description and its chunks, read as they are needed."""

    meta: dict
    handle: BinaryIO
    truncated: bool = False  # the file ends inside a record (the recorder was killed)

    def chunks(self) -> Iterator[tuple[float, bytes]]:
        with self.handle:
            while True:
                head = self.handle.read(RECORD.size)
                if not head:
                    return
                if len(head) < RECORD.size:
                    self.truncated = True
                    return
                seconds, length = RECORD.unpack(head)
                if length > MAX_CHUNK_BYTES or seconds != seconds:
                    raise damaged()
                chunk = self.handle.read(length)
                if len(chunk) < length:
                    self.truncated = True
                    if chunk:
                        yield seconds, chunk
                    return
                yield seconds, chunk


def damaged() -> UserError:
    return UserError("bridge.bad_recording")


def open_recording(path: Path) -> Recording:
    try:
        handle = path.open("rb")
    except OSError as error:
        raise UserError("bridge.cannot_read", path=str(path), error=error.strerror) from None
    if handle.read(len(MAGIC)) != MAGIC:
        handle.close()
        raise damaged()
    line = handle.readline(MAX_META_BYTES)
    try:
        meta = json.loads(line)
    except (ValueError, UnicodeDecodeError, RecursionError):
        handle.close()
        raise damaged() from None
    if not isinstance(meta, dict):
        handle.close()
        raise damaged()
    try:
        check_description(meta)
    except UserError:
        handle.close()
        raise
    return Recording(meta, handle)


TEXT_KEYS = ("format", "axis", "unit", "regex", "source", "started")
FLAG_KEYS = ("integrated", "mid_line")
COUNT_KEYS = ("column", "baud")
NUMBER_KEYS = ("rate_hz", "temperature_scale", "scale", "wall_clock_s")
AXES = ("x", "y", "z")
LATEST_CLOCK_S = 253_402_300_799.0  # the end of the year 9999: as far as datetime reads


def check_description(meta: dict) -> None:
    """A recording's description as the bridge wrote it (:func:`app.cli.bridge._meta`):
    each known value of its type and range, or ``bridge.damaged_description`` naming the
    first that is not (a damaged or hand-edited file was a traceback: a rate of 0 or a
    string, a clock of 1e300, NaN)."""
    for key, value in meta.items():
        if value is None or _usable(key, value):
            continue
        raise UserError("bridge.damaged_description", field=key[:40], value=str(value)[:40])


def _usable(key: str, value: object) -> bool:
    if key == "axis":
        return value in AXES  # as --axis chooses
    if key in TEXT_KEYS:
        return isinstance(value, str)
    if key in FLAG_KEYS:
        return isinstance(value, bool)
    if key in COUNT_KEYS:
        return isinstance(value, int) and not isinstance(value, bool) and value >= 1
    if key not in NUMBER_KEYS:
        return True  # kept, not used
    if isinstance(value, bool) or not isinstance(value, int | float):
        return False
    if not math.isfinite(value):
        return False
    if key == "rate_hz":
        return 0 < value <= MAX_RATE_HZ
    if key == "scale":
        return value != 0
    if key == "wall_clock_s":
        return 0 <= value <= LATEST_CLOCK_S
    return True


def paced(
    chunks: Iterator[tuple[float, bytes]], speed: float, sleep=time.sleep
) -> Iterator[tuple[float, bytes]]:
    """The chunks at their recorded pace divided by ``speed`` (0: as fast as possible)."""
    started = time.monotonic()
    for seconds, chunk in chunks:
        if speed > 0:
            wait = seconds / speed - (time.monotonic() - started)
            if wait > 0:
                sleep(wait)
        yield seconds, chunk
