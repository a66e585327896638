"""Samples into a session position through the REST API, in batches with offsets.

Each batch goes to ``POST /api/v1/sessions/{id}/{part}/positions/{k}/samples`` with the
index of its first sample as ``offset``; network errors and 5xx answers are retried with
back-off, and because of the offset a batch whose answer was lost is never stored twice.
Timed samples go as interleaved ``time_s, value`` float64 pairs (``columns=2``) or, in
JSON, with ``times_s``.
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
    attempts: int = 0
    binary: bool = True  # little-endian float64 bodies (8 bytes a sample); False: JSON
    timed: bool | None = None  # set by the first sample: every sample has a time, or none

    @property
    def url(self) -> str:
        return f"/api/v1/sessions/{self.session_id}/{self.part}/positions/{self.position}/samples"

    def add(self, value: float, time_s: float | None = None) -> None:
        if self.timed is None:
            self.timed = time_s is not None
        self.pending.append(value)
        if self.timed:
            self.pending_times.append(time_s if time_s is not None else float("nan"))
        if len(self.pending) >= self.batch:
            self.flush()

    def flush(self) -> None:
        while self.pending:
            chunk = self.pending[: self.batch]
            times = self.pending_times[: self.batch] if self.timed else None
            stored = self._post(chunk, times, self.sent)
            accepted = min(max(stored - self.sent, 0), len(chunk))
            self.sent = stored
            del self.pending[:accepted]
            del self.pending_times[:accepted]

    def _request(self, chunk: list[float], times: list[float] | None, offset: int) -> dict:
        """The POST's arguments: raw float64 with the unit and offset in the query, or JSON."""
        if self.binary:
            params = {"unit": self.unit, "offset": str(offset)}
            if times is None:
                body = np.asarray(chunk, dtype="<f8")
            else:
                body = np.column_stack([times, chunk]).astype("<f8")
                params["columns"] = "2"
            return {
                "content": body.tobytes(),
                "headers": {"Content-Type": "application/octet-stream"},
                "params": params,
            }
        payload: dict = {"samples": chunk, "unit": self.unit, "offset": offset}
        if times is not None:
            payload["times_s"] = times
        return {"json": payload}

    def _post(self, chunk: list[float], times: list[float] | None, offset: int) -> int:
        """POST with retries; returns the server's count of stored samples."""
        delay = self.backoff_s
        arguments = self._request(chunk, times, offset)
        for attempt in range(self.retries + 1):
            self.attempts += 1
            try:
                response = self.client.post(self.url, **arguments)
            except httpx.TransportError:
                if attempt == self.retries:
                    raise UserError("bridge.unreachable", "the server cannot be reached") from None
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
                    raise UserError(
                        "bridge.server_lost", f"the server lost samples: {detail}", detail=detail
                    )
            if response.status_code >= 400:
                raise UserError(
                    "bridge.refused",
                    f"upload refused ({response.status_code}): {detail}",
                    status_code=response.status_code,
                    detail=detail,
                )
            return int(response.json()["n_samples"])
        raise UserError("bridge.giving_up", "giving up after repeated errors")


def _detail(response: httpx.Response) -> str:
    try:
        return str(response.json().get("detail"))[:300]
    except (ValueError, AttributeError):
        return response.text[:200]
