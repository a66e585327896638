"""``gyrolab bridge``: move a gyro's readings from a serial port (or a file, or stdin) into
a session position through the REST API.

Each line the instrument prints is parsed with a regular expression (first group, or the
group named ``value``) or by column number, multiplied by a scale factor and sent in
batches to ``POST /api/v1/sessions/{id}/{part}/positions/{k}/samples`` with the index of
the batch's first sample as ``offset``.  Network errors and 5xx answers are retried with
back-off; because of the offset a batch whose answer was lost is never stored twice.
"""

from __future__ import annotations

import re
import sys
import time
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field

import httpx
import numpy as np

RETRY_STATUSES = {429, 500, 502, 503, 504}


class BridgeError(Exception):
    """A problem the user must fix (bad arguments, refused upload)."""


@dataclass
class LineParser:
    regex: re.Pattern | None = None
    column: int | None = None  # 1-based, split on commas, semicolons or white space
    scale: float = 1.0
    skipped: int = 0

    def parse(self, line: str) -> float | None:
        text = line.strip()
        if not text:
            return None
        try:
            if self.regex is not None:
                match = self.regex.search(text)
                if match is None:
                    raise ValueError
                groups = match.groupdict()
                raw = groups.get("value") or (match.group(1) if match.groups() else match.group(0))
            else:
                cells = [c for c in re.split(r"[,;\s]+", text) if c]
                raw = cells[(self.column or 1) - 1]
            value = float(raw) * self.scale
        except (ValueError, IndexError):
            self.skipped += 1
            return None
        if value != value or value in (float("inf"), float("-inf")):
            self.skipped += 1
            return None
        return value


def serial_lines(port: str, baud: int, timeout_s: float = 1.0) -> Iterator[str]:
    """Lines from a serial port (pyserial), decoded leniently.  The port opens at once;
    an empty string is yielded whenever nothing arrived for ``timeout_s`` so that time
    limits are still checked."""
    import serial

    try:
        connection = serial.Serial(port, baudrate=baud, timeout=timeout_s)
    except serial.SerialException as error:
        raise BridgeError(f"cannot open {port}: {error}") from None

    def lines() -> Iterator[str]:
        with connection:
            while True:
                raw = connection.readline()
                yield raw.decode("ascii", errors="replace") if raw else ""

    return lines()


@dataclass
class Uploader:
    client: httpx.Client
    session_id: int
    part: str
    position: int
    unit: str = "deg/h"
    batch: int = 50
    retries: int = 8
    backoff_s: float = 0.5
    sent: int = 0  # samples acknowledged by the server
    pending: list[float] = field(default_factory=list)
    attempts: int = 0
    binary: bool = True  # little-endian float64 bodies (8 bytes a sample); False: JSON

    @property
    def url(self) -> str:
        return f"/api/v1/sessions/{self.session_id}/{self.part}/positions/{self.position}/samples"

    def add(self, value: float) -> None:
        self.pending.append(value)
        if len(self.pending) >= self.batch:
            self.flush()

    def flush(self) -> None:
        while self.pending:
            chunk = self.pending[: self.batch]
            stored = self._post(chunk, self.sent)
            accepted = min(max(stored - self.sent, 0), len(chunk))
            self.sent = stored
            del self.pending[:accepted]

    def _request(self, chunk: list[float], offset: int) -> dict:
        """The POST's arguments: raw float64 with the unit and offset in the query, or JSON."""
        if self.binary:
            return {
                "content": np.asarray(chunk, dtype="<f8").tobytes(),
                "headers": {"Content-Type": "application/octet-stream"},
                "params": {"unit": self.unit, "offset": str(offset)},
            }
        return {"json": {"samples": chunk, "unit": self.unit, "offset": offset}}

    def _post(self, chunk: list[float], offset: int) -> int:
        """POST with retries; returns the server's count of stored samples."""
        delay = self.backoff_s
        arguments = self._request(chunk, offset)
        for attempt in range(self.retries + 1):
            self.attempts += 1
            try:
                response = self.client.post(self.url, **arguments)
            except httpx.TransportError:
                if attempt == self.retries:
                    raise BridgeError("the server cannot be reached") from None
                time.sleep(delay)
                delay = min(delay * 2, 10.0)
                continue
            if response.status_code in RETRY_STATUSES and attempt < self.retries:
                time.sleep(delay)
                delay = min(delay * 2, 10.0)
                continue
            if response.status_code == 409:
                detail = response.json().get("detail", "")
                match = re.search(r"Expected offset (\d+)", detail)
                if match and int(match.group(1)) < offset:
                    raise BridgeError(f"the server lost samples: {detail}")
            if response.status_code >= 400:
                try:
                    detail = response.json().get("detail")
                except ValueError:
                    detail = response.text[:200]
                raise BridgeError(f"upload refused ({response.status_code}): {detail}")
            return int(response.json()["n_samples"])
        raise BridgeError("giving up after repeated errors")


def run_bridge(
    lines: Iterable[str],
    parser: LineParser,
    uploader: Uploader,
    *,
    max_samples: int | None = None,
    seconds: float | None = None,
    progress=sys.stderr,
) -> int:
    """Read, parse and upload until the input ends or a limit is reached; returns the count."""
    start = time.monotonic()
    read = 0
    for line in lines:
        value = parser.parse(line)
        if value is not None:
            uploader.add(value)
            read += 1
            if progress is not None and read % uploader.batch == 0:
                print(
                    f"\r{read} readings read, {uploader.sent} stored",
                    end="",
                    file=progress,
                    flush=True,
                )
        if max_samples is not None and read >= max_samples:
            break
        if seconds is not None and time.monotonic() - start >= seconds:
            break
    uploader.flush()
    if progress is not None:
        print(
            f"\r{read} readings read, {uploader.sent} stored, {parser.skipped} lines skipped",
            file=progress,
            flush=True,
        )
    return uploader.sent
