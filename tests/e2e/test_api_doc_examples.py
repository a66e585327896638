"""The API examples of docs/api.md, run as written against a live server."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.e2e.conftest import STUDENT_PASSWORD

pytestmark = pytest.mark.e2e
ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "tests" / "data"


def example(kind: str) -> str:
    text = (ROOT / "docs" / "api.md").read_text()
    match = re.search(rf"<!-- example:{kind} -->\n```\w+\n(.*?)```\n<!-- /example -->", text, re.S)
    assert match, f"docs/api.md has no {kind} example"
    return match.group(1)


def environment(server) -> dict[str, str]:
    return {
        **server.env,
        "GYROLAB_URL": server.url,
        "GYROLAB_USER": "student",
        "GYROLAB_PASSWORD": STUDENT_PASSWORD,
    }


def test_curl_example(live_server):
    if shutil.which("curl") is None:
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail("curl is needed for the curl example of docs/api.md")
        pytest.skip("curl is not installed")
    done = subprocess.run(
        ["bash", "-euo", "pipefail", "-c", example("curl")],
        cwd=DATA,
        env=environment(live_server),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 0, done.stderr
    assert '"theta_deg":-10.75' in done.stdout.replace(" ", "")


def test_python_example(any_live_server):
    done = subprocess.run(
        [sys.executable, "-c", example("python")],
        cwd=DATA,
        env=environment(any_live_server),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == [
        "theta -10.75 latitude 40.73 earth rate 15.133",
        "submitted",
    ]
