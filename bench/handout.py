"""A practice session holding the handout's two tables, made through the REST API: what
the web benchmarks read back."""

from __future__ import annotations

import csv
from pathlib import Path

import httpx

DATA = Path(__file__).resolve().parents[1] / "tests" / "data"


def handout_session(client: httpx.Client, auth: dict, title: str = "bench") -> int:
    """A new session with the handout's 4 horizontal and 4 vertical positions (10 readings
    each); its id."""
    session = client.post(
        "/api/v1/sessions",
        headers=auth,
        json={"title": title, "station": {"latitude_deg": 39.93, "earth_rate_deg_h": 15.04}},
    ).json()["id"]
    for part, name in (("heading", "handout_horizontal.csv"), ("latitude", "handout_vertical.csv")):
        with open(DATA / name) as handle:
            rows = list(csv.DictReader(handle))
        for k in range(1, 5):
            client.put(
                f"/api/v1/sessions/{session}/{part}/positions/{k}",
                headers=auth,
                json={"samples": [float(r[f"position_{k}"]) for r in rows]},
            ).raise_for_status()
    return session
