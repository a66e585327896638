"""Where the bytes come from: a serial port, a file or standard input.  Each source
yields ``(seconds since it opened, bytes)``; a serial port yields an empty chunk whenever
nothing arrived for a while, so that time limits are still checked."""

from __future__ import annotations

import time
from collections.abc import Iterator
from typing import BinaryIO

from app.core.exceptions import UserError

READ_BYTES = 65536  # the most read at once: 0.7 s of a DSP-1750 at 921600 baud


def serial_chunks(port: str, baud: int, timeout_s: float = 0.2) -> Iterator[tuple[float, bytes]]:
    """Bytes from a serial port (pyserial, 8N1).  The port opens at once, so that the
    caller knows before reading whether it exists."""
    import serial

    try:
        connection = serial.Serial(port, baudrate=baud, timeout=timeout_s)
    except (serial.SerialException, ValueError) as error:
        raise UserError("bridge.cannot_open", port=port, error=str(error)) from None

    def chunks() -> Iterator[tuple[float, bytes]]:
        started = time.monotonic()
        with connection:
            while True:
                waiting = connection.in_waiting
                data = connection.read(min(max(waiting, 1), READ_BYTES))
                yield time.monotonic() - started, data

    return chunks()


def stream_chunks(handle: BinaryIO, size: int = 4096) -> Iterator[tuple[float, bytes]]:
    """Bytes from a file or a pipe until it ends."""
    started = time.monotonic()
    with handle:
        while True:
            data = handle.read1(size) if hasattr(handle, "read1") else handle.read(size)
            if not data:
                return
            yield time.monotonic() - started, data
