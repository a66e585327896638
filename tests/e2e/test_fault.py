"""Fault test: kill -9 the server in the middle of uploads and streams, restart it, and show
the database is intact, holds every acknowledged write and no half-written position."""

from __future__ import annotations

import os
import signal
import sqlite3
import threading
import time

import httpx
import pytest
import websockets.sync.client as ws_client

from tests.e2e.conftest import STUDENT_PASSWORD, running_server

pytestmark = pytest.mark.e2e


def login(url: str) -> httpx.Client:
    client = httpx.Client(base_url=url, timeout=10)
    token = client.post(
        "/api/v1/auth/token", data={"username": "student", "password": STUDENT_PASSWORD}
    ).json()
    client.headers["Authorization"] = f"Bearer {token['access_token']}"
    return client


def test_kill_9_loses_no_acknowledged_write(live_server, tmp_path):
    url = live_server.url
    api = login(url)
    sessions = [
        api.post(
            "/api/v1/sessions",
            json={
                "title": f"fault {i}",
                "station": {"latitude_deg": 39.93, "earth_rate_deg_h": 15.04},
            },
        ).json()["id"]
        for i in range(3)
    ]
    acknowledged: list[tuple[int, int, int]] = []  # (session, position, n_samples)
    stop = threading.Event()

    def uploader(session_id: int) -> None:
        client = login(url)
        batch = 0
        while not stop.is_set():
            position = batch % 4 + 1
            samples = [10.0 + batch + i / 1000 for i in range(5000)]
            try:
                reply = client.put(
                    f"/api/v1/sessions/{session_id}/heading/positions/{position}",
                    json={"samples": samples},
                )
            except httpx.HTTPError:
                return  # the server died under us: this upload was never acknowledged
            if reply.status_code == 200:
                acknowledged.append((session_id, position, batch))
            batch += 1

    # a live simulator stream as well (its position must be all or nothing)
    cookie_client = httpx.Client(base_url=url, timeout=10)
    page = cookie_client.get("/login")
    csrf = page.text.split('name="csrf_token" value="')[1].split('"')[0]
    cookie_client.post(
        "/login", data={"username": "student", "password": STUDENT_PASSWORD, "csrf_token": csrf}
    )
    cookie = cookie_client.cookies.get("gyrolab_session")
    stream_session = sessions[0]

    def streamer() -> None:
        try:
            with ws_client.connect(
                f"ws://{url.removeprefix('http://')}/lab/sessions/{stream_session}/stream",
                additional_headers={"Cookie": f"gyrolab_session={cookie}"},
            ) as ws:
                ws.send(
                    '{"action": "start", "part": "latitude", "position": 1, '
                    '"dwell_s": 600, "speed": 1}'
                )
                while not stop.is_set():
                    ws.recv(timeout=5)
        except Exception:  # noqa: BLE001  (the server is killed mid-stream on purpose)
            return

    threads = [threading.Thread(target=uploader, args=(s,)) for s in sessions]
    threads.append(threading.Thread(target=streamer))
    for thread in threads:
        thread.start()
    time.sleep(3.0)
    assert live_server.process is not None
    os.kill(live_server.process.pid, signal.SIGKILL)
    time.sleep(0.5)
    stop.set()
    for thread in threads:
        thread.join(15)
    assert len(acknowledged) >= 3, "too few uploads finished before the kill"

    database = live_server.var_dir / "gyrolab.db"
    connection = sqlite3.connect(database)
    assert connection.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
    connection.close()
    with running_server(live_server.var_dir, "--no-demo") as restarted:
        check = login(restarted.url)
        for session_id in sessions:
            detail = check.get(f"/api/v1/sessions/{session_id}").json()
            stored = {
                p["position"]: p["n_samples"] for p in detail["positions"] if p["part"] == "heading"
            }
            for acked_session, position, _batch in acknowledged:
                if acked_session == session_id:
                    assert stored.get(position) == 5000  # every acknowledged write is there
        page = cookie_client.get(f"{restarted.url}/lab/sessions/{stream_session}")
        assert page.status_code == 200
        assert "was interrupted and not saved" in page.text  # the stream died mid-position
        streamed = check.get(f"/api/v1/sessions/{stream_session}").json()["positions"]
        assert not [p for p in streamed if p["part"] == "latitude"]  # nothing half-saved
    connection = sqlite3.connect(database)
    # no half-written position: every take's samples add up to its count
    rows = connection.execute(
        'SELECT take.id, take.n_samples, SUM(LENGTH(sample_chunk."values")) / 8 '
        "FROM take JOIN sample_chunk ON sample_chunk.take_id = take.id GROUP BY take.id"
    ).fetchall()
    orphans = connection.execute(
        "SELECT COUNT(*) FROM take WHERE id NOT IN (SELECT take_id FROM sample_chunk)"
    ).fetchone()[0]
    connection.close()
    assert rows and all(n == total for _, n, total in rows)
    assert orphans == 0
