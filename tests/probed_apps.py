"""Small FastAPI apps for the benchmark probes' tests (``bench/probe/sitecustomize.py``):
a script run in a subprocess with the probe on its ``PYTHONPATH``, routes that burn a known
amount of CPU (by the thread's own clock), called one after another."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

PROBE = Path(__file__).resolve().parents[1] / "bench" / "probe"

HEAD = """
import asyncio, time
import httpx
from fastapi import Depends, FastAPI

app = FastAPI()

def burn(seconds):
    began = time.thread_time()
    while time.thread_time() - began < seconds:
        pass
"""

MAIN = """
async def main():
    transport = httpx.ASGITransport(app=app)
    async with httpx.AsyncClient(transport=transport, base_url="http://t") as client:
{calls}

asyncio.run(main())
"""


def run_probed(routes: str, calls: list[str], env: dict[str, str]) -> None:
    """Serve ``routes`` (the app's route functions, as source) in a fresh interpreter with
    the probe loaded and ``env`` set, making ``calls`` (awaitable expressions on
    ``client``) one after another."""
    lines = "\n".join(f"        await {call}" for call in calls)
    script = HEAD + routes + MAIN.format(calls=lines)
    full = {**os.environ, "PYTHONPATH": str(PROBE), **env}
    done = subprocess.run([sys.executable, "-c", script], env=full, timeout=60, capture_output=True)
    errors = done.stderr.decode(errors="replace")
    assert done.returncode == 0, errors
    # Python reports an error in sitecustomize on stderr and runs on without the rest of it
    assert "Error in sitecustomize" not in errors, errors
