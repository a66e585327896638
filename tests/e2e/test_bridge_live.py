"""``gyrolab bridge`` as a real process: a pseudo-terminal FOG → the live server."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time

import httpx
import pytest

from tests.e2e.conftest import STUDENT_PASSWORD

pytestmark = pytest.mark.e2e


def test_bridge_moves_a_pty_stream_into_a_session(live_server):
    api = httpx.Client(base_url=live_server.url, timeout=10)
    token = api.post(
        "/api/v1/auth/token", data={"username": "student", "password": STUDENT_PASSWORD}
    ).json()
    api.headers["Authorization"] = f"Bearer {token['access_token']}"
    session = api.post(
        "/api/v1/sessions",
        json={"title": "bridge", "station": {"latitude_deg": 39.93, "earth_rate_deg_h": 15.04}},
    ).json()
    master, slave = os.openpty()
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "app.cli.main",
            "bridge",
            "--serial",
            os.ttyname(slave),
            "--baud",
            "115200",
            "--url",
            live_server.url,
            "--token",
            token["access_token"],
            "--session",
            str(session["id"]),
            "--part",
            "heading",
            "--position",
            "1",
            "--regex",
            r"^\$FOG,\d+,(?P<value>[-0-9.]+),",
            "--scale",
            "3600",
            "--batch",
            "20",
            "--max-samples",
            "60",
            "--seconds",
            "60",
        ],
        env=live_server.env,
        stderr=subprocess.PIPE,
        text=True,
    )
    stop = threading.Event()

    def instrument():
        index = 0
        while not stop.is_set() and index < 2000:
            os.write(master, f"$FOG,{index},{(10 + index / 1000) / 3600:.9f},24.1\r\n".encode())
            index += 1
            time.sleep(0.01)

    writer = threading.Thread(target=instrument, daemon=True)
    writer.start()
    try:
        _, errors = process.communicate(timeout=60)
    finally:
        stop.set()
        writer.join(5)
        os.close(master)
        os.close(slave)
    assert process.returncode == 0, errors
    assert "60 readings read, 60 stored" in errors
    detail = api.get(f"/api/v1/sessions/{session['id']}").json()
    assert detail["positions"][0]["n_samples"] == 60
    assert detail["positions"][0]["source"] == "api"
