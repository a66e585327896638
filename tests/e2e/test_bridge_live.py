"""``gyrolab bridge`` as a real process: a pseudo-terminal FOG → the live server."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time

import httpx
import numpy as np
import pytest

from app.bridge.recording import Recorder
from tests.e2e.conftest import STUDENT_PASSWORD
from tests.instrument_streams import dsp1750_stream
from tests.loopback import TLS

pytestmark = pytest.mark.e2e


def test_bridge_moves_a_pty_stream_into_a_session(live_server):
    api = httpx.Client(base_url=live_server.url, timeout=10, verify=TLS)
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
    assert "60 samples made, 60 stored" in errors
    detail = api.get(f"/api/v1/sessions/{session['id']}").json()
    assert detail["positions"][0]["n_samples"] == 60
    assert detail["positions"][0]["source"] == "api"


def test_a_recorded_dsp1750_run_replays_into_a_session(live_server, tmp_path):
    """What a class does with a teacher's capture: replay it through the real command."""
    api = httpx.Client(base_url=live_server.url, timeout=10, verify=TLS)
    token = api.post(
        "/api/v1/auth/token", data={"username": "student", "password": STUDENT_PASSWORD}
    ).json()["access_token"]
    api.headers["Authorization"] = f"Bearer {token}"
    session = api.post(
        "/api/v1/sessions",
        json={"title": "replay", "station": {"latitude_deg": 39.93, "earth_rate_deg_h": 15.04}},
    ).json()
    rates = 12.0 + 0.01 * np.arange(400)  # the values and times are checked in test_bridge
    recording = tmp_path / "capture.gyroraw"
    recorder = Recorder(recording, {"format": "kvh-dsp1750", "wall_clock_s": 1.7e9})
    frames = dsp1750_stream(rates)
    for index in range(0, 400, 50):
        recorder.write(index / 1000, b"".join(frames[index : index + 50]))
    recorder.close()
    command = [sys.executable, "-m", "app.cli.main", "bridge", "--replay", str(recording)]
    command += ["--speed", "0", "--url", live_server.url, "--token", token, "--language", "en"]
    command += ["--session", str(session["id"]), "--part", "heading", "--position", "2"]
    done = subprocess.run(command, env=live_server.env, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert "400 samples made, 400 stored" in done.stderr and "No gaps" in done.stderr
    detail = api.get(f"/api/v1/sessions/{session['id']}").json()
    (position,) = [p for p in detail["positions"] if p["position"] == 2]
    assert position["n_samples"] == 400 and position["source"] == "api"
