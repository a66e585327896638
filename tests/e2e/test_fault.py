"""Fault test: kill -9 the server in the middle of uploads and streams, restart it, and show
the database is intact, holds every acknowledged write and no half-written position.

Runs on SQLite (one worker) and on PostgreSQL (two workers, both killed at once)."""

from __future__ import annotations

import sqlite3
import threading
import time
from collections.abc import Iterator

import httpx
import numpy as np
import pytest
import websockets.sync.client as ws_client
from sqlalchemy import create_engine, text

from tests.e2e.conftest import STUDENT_PASSWORD, LiveServer, new_live_server
from tests.loopback import TLS

pytestmark = pytest.mark.e2e


def login(url: str) -> httpx.Client:
    client = httpx.Client(base_url=url, timeout=10, verify=TLS)
    token = client.post(
        "/api/v1/auth/token", data={"username": "student", "password": STUDENT_PASSWORD}
    ).json()
    client.headers["Authorization"] = f"Bearer {token['access_token']}"
    return client


@pytest.fixture(params=["sqlite", "postgresql"])
def server_to_kill(request, tmp_path) -> Iterator[LiveServer]:
    """A server of this test's own (the shared ones must live on)."""
    postgres = request.getfixturevalue("postgres") if request.param == "postgresql" else None
    with new_live_server(tmp_path, postgres) as server:
        yield server


def test_kill_9_loses_no_acknowledged_write(server_to_kill: LiveServer):
    live_server = server_to_kill
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
    acknowledged: list[tuple[int, int, int]] = []  # (session, position, batch)
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
    cookie_client = httpx.Client(base_url=url, timeout=10, verify=TLS)
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
    live_server.kill_9()
    stop.set()
    for thread in threads:
        thread.join(15)
    assert len(acknowledged) >= 3, "too few uploads finished before the kill"

    if live_server.database_url is None:
        connection = sqlite3.connect(live_server.var_dir / "gyrolab.db")
        assert connection.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
        connection.close()
    with live_server.restarted() as restarted:
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
    assert_no_half_written_take(live_server)
    assert_latest_acknowledged_batches_stored(live_server, acknowledged)


def database_engine(server: LiveServer):
    return create_engine(server.database_url or f"sqlite:///{server.var_dir / 'gyrolab.db'}")


def assert_no_half_written_take(server: LiveServer) -> None:
    """Every take's chunks add up to its sample count, and no take is without chunks."""
    engine = database_engine(server)
    with engine.connect() as connection:
        rows = connection.execute(
            text(
                'SELECT take.id, take.n_samples, SUM(LENGTH(sample_chunk."values")) / 8 '
                "FROM take JOIN sample_chunk ON sample_chunk.take_id = take.id GROUP BY take.id"
            )
        ).all()
        orphans = connection.execute(
            text("SELECT COUNT(*) FROM take WHERE id NOT IN (SELECT take_id FROM sample_chunk)")
        ).scalar_one()
    engine.dispose()
    assert rows and all(n == total for _, n, total in rows)
    assert orphans == 0


def assert_latest_acknowledged_batches_stored(server: LiveServer, acknowledged) -> None:
    """The current take of each position holds the last acknowledged upload (or a later one
    whose reply was cut off by the kill), never an older one."""
    latest: dict[tuple[int, int], int] = {}
    for session_id, position, batch in acknowledged:
        latest[session_id, position] = max(batch, latest.get((session_id, position), -1))
    engine = database_engine(server)
    with engine.connect() as connection:
        for (session_id, position), batch in latest.items():
            first_chunk = connection.execute(
                text(
                    'SELECT sample_chunk."values" FROM take JOIN sample_chunk'
                    " ON sample_chunk.take_id = take.id WHERE take.session_id = :s"
                    " AND take.part = 'heading' AND take.position = :p"
                    " AND take.superseded_at IS NULL AND sample_chunk.seq = 0"
                ),
                {"s": session_id, "p": position},
            ).scalar_one()
            stored_batch = round(np.frombuffer(first_chunk, "<f8")[0] - 10.0)
            assert stored_batch >= batch
    engine.dispose()
