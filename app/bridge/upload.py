"""Samples into a session position through the REST API, in batches with offsets.

Each batch goes to ``POST /api/v1/sessions/{id}/{part}/positions/{k}/samples`` with the
index of its first sample as ``offset``; network errors and 5xx answers are retried with
back-off, and because of the offset a batch whose answer was lost is never stored twice.
Timed samples go as interleaved ``time_s, value`` float64 pairs (``columns=2``), or
``time_s, value, temperature_c`` triples (``columns=3``) when the gyro reports its
temperature; in JSON, with ``times_s`` and ``temperatures_c``.
"""

from __future__ import annotations

import re
import time
from dataclasses import dataclass, field

import httpx
import numpy as np

from app.core.exceptions import UserError

RETRY_STATUSES = {429, 500, 502, 503, 504}


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
    pending_times: list[float] = field(default_factory=list)
    pending_temperatures: list[float] = field(default_factory=list)
    attempts: int = 0
    binary: bool = True  # little-endian float64 bodies (8 bytes a sample); False: JSON
    # set by the first sample: every sample has a time (a temperature), or none has
    timed: bool | None = None
    with_temperatures: bool | None = None

    @property
    def url(self) -> str:
        return f"/api/v1/sessions/{self.session_id}/{self.part}/positions/{self.position}/samples"

    def add(
        self, value: float, time_s: float | None = None, temperature_c: float | None = None
    ) -> None:
        if self.timed is None:
            self.timed = time_s is not None
            self.with_temperatures = temperature_c is not None
        self.pending.append(value)
        if self.timed:
            self.pending_times.append(time_s if time_s is not None else float("nan"))
        if self.with_temperatures:
            self.pending_temperatures.append(
                temperature_c if temperature_c is not None else float("nan")
            )
        if len(self.pending) >= self.batch:
            self.flush()

    def flush(self) -> None:
        while self.pending:
            chunk = self.pending[: self.batch]
            times = self.pending_times[: self.batch] if self.timed else None
            temperatures = (
                self.pending_temperatures[: self.batch] if self.with_temperatures else None
            )
            stored = self._post(self._request(chunk, times, temperatures, self.sent), self.sent)
            accepted = min(max(stored - self.sent, 0), len(chunk))
            self.sent = stored
            del self.pending[:accepted]
            del self.pending_times[:accepted]
            del self.pending_temperatures[:accepted]

    def _request(
        self,
        chunk: list[float],
        times: list[float] | None,
        temperatures: list[float] | None,
        offset: int,
    ) -> dict:
        """The POST's arguments: raw float64 columns with the unit and offset in the query,
        or JSON (also for temperatures without times, which have no binary layout)."""
        if self.binary and (times is not None or temperatures is None):
            params = {"unit": self.unit, "offset": str(offset)}
            if times is None:
                body = np.asarray(chunk, dtype="<f8")
            else:
                columns = [times, chunk] + ([temperatures] if temperatures is not None else [])
                body = np.column_stack(columns).astype("<f8")
                params["columns"] = str(len(columns))
            return {
                "content": body.tobytes(),
                "headers": {"Content-Type": "application/octet-stream"},
                "params": params,
            }
        payload: dict = {"samples": chunk, "unit": self.unit, "offset": offset}
        if times is not None:
            payload["times_s"] = times
        if temperatures is not None:
            payload["temperatures_c"] = temperatures
        return {"json": payload}

    def _post(self, arguments: dict, offset: int) -> int:
        """POST with retries; returns the server's count of stored samples."""
        delay = self.backoff_s
        for attempt in range(self.retries + 1):
            self.attempts += 1
            try:
                response = self.client.post(self.url, **arguments)
            except httpx.TransportError:
                if attempt == self.retries:
                    raise UserError("bridge.unreachable") from None
                time.sleep(delay)
                delay = min(delay * 2, 10.0)
                continue
            if response.status_code in RETRY_STATUSES and attempt < self.retries:
                time.sleep(delay)
                delay = min(delay * 2, 10.0)
                continue
            detail = _detail(response) if response.status_code >= 400 else ""
            if response.status_code == 409:
                match = re.search(r"Expected offset (\d+)", detail)
                if match and int(match.group(1)) < offset:
                    raise UserError("bridge.server_lost", detail=detail)
            if response.status_code >= 400:
                raise UserError(
                    "bridge.refused",
                    status_code=response.status_code,
                    detail=detail,
                )
            return int(response.json()["n_samples"])
        raise UserError("bridge.giving_up")


def _detail(response: httpx.Response) -> str:
    try:
        return str(response.json().get("detail"))[:300]
    except (ValueError, AttributeError):
        return response.text[:200]
