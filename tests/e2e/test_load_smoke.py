"""The load test (bench/load_test.py) in miniature, so that it keeps working: a few students
on SQLite and on PostgreSQL with two workers, no errors and no lost samples."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.e2e
ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("database", ["sqlite", "postgresql"])
def test_load_test_runs_clean(database, request):
    extra = []
    if database == "postgresql":  # skips (or fails in CI) without PostgreSQL
        postgres = request.getfixturevalue("postgres")
        name, url = postgres.new_database()
        request.addfinalizer(lambda: postgres.server.drop_database(name))
        extra = ["--database-url", url]  # the tests' server: no cluster of its own to start
    done = subprocess.run(
        [
            sys.executable,
            str(ROOT / "bench" / "load_test.py"),
            "--students",
            "3",
            "--backend",
            database,
            "--dwell",
            "5",
            "--speed",
            "60",
            "--ramp",
            "0.5",
            *extra,
        ],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=ROOT,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert "errors: 0; lost samples: 0 of 48 positions checked" in done.stdout
    assert "| POST /lab/sessions/{id}/submit | 3 |" in done.stdout
    assert "CPU used during the class: server " in done.stdout  # the queueing model's check
    # whether the host kept the cores from the class, said of every run (its p95s' worth)
    assert "the host's steal during the class (/proc/stat): " in done.stdout
    # frames go uncompressed: compressing each cost most of a frame's CPU (bench/README.md)
    assert "WebSocket extensions the server agreed to: none" in done.stdout
