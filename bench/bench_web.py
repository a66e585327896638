"""Web benchmarks on loopback, each with its ceiling measured in the same run.

    .venv/bin/python bench/bench_web.py [--requests 300]

Starts GyroLab (``gyrolab serve``, no access log) and a bare FastAPI app on free
127.0.0.1 ports, then measures sequential request rates: the results endpoint against a
bare JSON endpoint, the lab page against a bare Jinja page; an upload of 1e6 samples (as
JSON and as raw float64) plus solving them against writing the same array as one BLOB with
sqlite3; 60 logins; and the
teacher dashboard of an assignment with 300 submissions.  Bounded in count and time.
"""

from __future__ import annotations

import argparse
import os
import platform
import socket
import sqlite3
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import httpx
import numpy as np
from handout import handout_session  # bench/, the script's folder

ARGON2 = "m=7 MiB, t=5"  # app.accounts.security (this script does not import the app)

ROOT = Path(__file__).resolve().parents[1]
PASSWORD = "bench-password-1"


def free_ports(count: int) -> list[int]:
    """``count`` distinct free loopback ports (each held until all are chosen: two choices
    one after the other can return the same port)."""
    sockets = [socket.socket() for _ in range(count)]
    try:
        for sock in sockets:
            sock.bind(("127.0.0.1", 0))
        return [sock.getsockname()[1] for sock in sockets]
    finally:
        for sock in sockets:
            sock.close()


def wait_for(url: str, process: subprocess.Popen) -> None:
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        if process.poll() is not None:
            raise RuntimeError("server exited")
        try:
            httpx.get(url, timeout=1)
            return
        except httpx.HTTPError:
            time.sleep(0.2)
    raise RuntimeError(f"{url} did not answer")


def rate(client: httpx.Client, url: str, count: int, **kwargs) -> float:
    """Requests per second for ``count`` sequential GETs (after a short warm-up)."""
    for _ in range(10):
        client.get(url, **kwargs).raise_for_status()
    start = time.perf_counter()
    for _ in range(count):
        client.get(url, **kwargs).raise_for_status()
    return count / (time.perf_counter() - start)


def median_of(count: int, run) -> float:
    """The median wall time of ``count`` runs of ``run(k)`` (k = 0 … count − 1), in s."""
    times = []
    for k in range(count):
        start = time.perf_counter()
        run(k)
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def blob_write(path: Path, values: np.ndarray) -> None:
    """The baseline: one array written as one BLOB into a new SQLite file, committed."""
    connection = sqlite3.connect(path)
    connection.execute("CREATE TABLE t (b BLOB)")
    with connection:
        connection.execute("INSERT INTO t VALUES (?)", (values.astype("<f8").tobytes(),))
    connection.close()


def seed_dashboard(env: dict, students: int) -> None:
    """An assignment with ``students`` submitted sessions, written straight to the database."""
    code = f"""
import numpy as np
from app.db import write_session
from app.models import Assignment, Course, Enrollment, LabSession, Role, User
from app.lab.store import store_take
from app.lab.submissions import submit
from app.accounts.security import hash_password
with write_session() as db:
    teacher = db.exec(__import__('sqlmodel').select(User).where(User.username == 'teacher')).one()
    course = Course(name='Bench class', teacher_id=teacher.id); db.add(course); db.flush()
    assignment = Assignment(course_id=course.id, title='Bench', latitude_deg=39.93,
                            earth_rate_deg_h=15.04, true_heading_deg=10.8)
    db.add(assignment); db.flush()
    password = hash_password('x' * 12)
    rng = np.random.default_rng(1)
    for i in range({students}):
        user = User(username=f'b{{i:04d}}', display_name=f'学生{{i}}', role='student',
                    password_hash=password)
        db.add(user); db.flush()
        db.add(Enrollment(course_id=course.id, student_id=user.id))
        session = LabSession(owner_id=user.id, assignment_id=assignment.id, title='Bench',
                             latitude_deg=39.93, earth_rate_deg_h=15.04)
        db.add(session); db.flush()
        for part, means in (('heading', [10.7, 2.8, -8.95, -0.94]),
                            ('latitude', [11.13, 9.82, -11.8, -9.92])):
            for k, mean in enumerate(means, start=1):
                angle = -90.0 * (k - 1) if part == 'heading' else 90.0 * (k - 1)
                store_take(db, session, part=part, position=k, angle_deg=angle,
                           values=rng.normal(mean, 0.1, 10), times=None, source='api')
        submit(db, session)
    print(assignment.id, course.id)
"""
    done = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    return [int(x) for x in done.stdout.split()]


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--requests", type=int, default=300)
    parser.add_argument("--students", type=int, default=300)
    args = parser.parse_args()
    results: list[tuple[str, str, str]] = []
    with tempfile.TemporaryDirectory() as var:
        env = {**os.environ, "GYROLAB_VAR_DIR": var}
        for role, name in (("teacher", "teacher"), ("student", "student")):
            subprocess.run(
                [
                    sys.executable,
                    "-m",
                    "app.cli.main",
                    "create-user",
                    "--role",
                    role,
                    "--username",
                    name,
                ],
                input=PASSWORD + "\n",
                env=env,
                text=True,
                check=True,
                capture_output=True,
            )
        port, bare_port = free_ports(2)
        app = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "app.cli.main",
                "serve",
                "--no-demo",
                "--no-access-log",
                "--port",
                str(port),
            ],
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        bare = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "uvicorn",
                "bare_app:app",
                "--port",
                str(bare_port),
                "--no-access-log",
                "--log-level",
                "warning",
            ],
            cwd=ROOT / "bench",
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        try:
            url, bare_url = f"http://127.0.0.1:{port}", f"http://127.0.0.1:{bare_port}"
            wait_for(f"{url}/login", app)
            wait_for(f"{bare_url}/json", bare)
            client = httpx.Client(base_url=url, timeout=60)
            bare_client = httpx.Client(base_url=bare_url, timeout=60)
            token = client.post(
                "/api/v1/auth/token", data={"username": "student", "password": PASSWORD}
            ).json()
            auth = {"Authorization": f"Bearer {token['access_token']}"}
            session = handout_session(client, auth)
            n = args.requests
            ours = rate(client, f"/api/v1/sessions/{session}/results", n, headers=auth)
            ceiling = rate(bare_client, "/json", n)
            results.append(
                (
                    "results endpoint (req/s)",
                    f"{ours:.0f}",
                    f"bare JSON {ceiling:.0f} req/s → {ours / ceiling:.2f}×",
                )
            )
            browser = httpx.Client(base_url=url, timeout=60)
            page = browser.get("/login")
            csrf = page.text.split('name="csrf_token" value="')[1].split('"')[0]
            browser.post(
                "/login", data={"username": "student", "password": PASSWORD, "csrf_token": csrf}
            )
            lab_page = f"/lab/sessions/{session}"
            size = len(browser.get(lab_page).content)
            ours = rate(browser, lab_page, max(n // 3, 30))
            sized = rate(bare_client, f"/page/{size}", max(n // 3, 30))
            small = rate(bare_client, "/page", max(n // 3, 30))
            results.append(
                (
                    "lab page with results and charts (req/s)",
                    f"{ours:.0f}",
                    f"bare Jinja page of its size ({size / 1000:.0f} kB) {sized:.0f} req/s"
                    f" → {ours / sized:.2f}×; a 0.4 kB bare page {small:.0f} req/s"
                    f" → {ours / small:.2f}×",
                )
            )

            big = np.random.default_rng(0).normal(10.0, 0.1, 1_000_000)
            start = time.perf_counter()
            client.put(
                f"/api/v1/sessions/{session}/heading/positions/1",
                headers=auth,
                json={"samples": big.tolist()},
            ).raise_for_status()
            client.get(f"/api/v1/sessions/{session}/results", headers=auth).raise_for_status()
            ours = time.perf_counter() - start
            ceiling = median_of(5, lambda k: blob_write(Path(var) / f"raw{k}.db", big))
            results.append(
                (
                    "upload 1e6 samples (JSON) + solve (s)",
                    f"{ours:.2f}",
                    f"sqlite3 BLOB write {ceiling * 1000:.0f} ms → {ours / ceiling:.0f}×",
                )
            )

            def upload(content_type: str, body: bytes) -> None:
                client.put(
                    f"/api/v1/sessions/{session}/heading/positions/1",
                    headers={**auth, "Content-Type": content_type},
                    content=body,
                ).raise_for_status()
                client.get(f"/api/v1/sessions/{session}/results", headers=auth).raise_for_status()

            raw = big.astype("<f8").tobytes()
            binary = median_of(5, lambda _k: upload("application/octet-stream", raw))
            results.append(
                (
                    "upload 1e6 samples (raw float64) + solve (s, median of 5)",
                    f"{binary:.3f}",
                    f"sqlite3 BLOB write {ceiling * 1000:.0f} ms (median of 5) "
                    f"→ {binary / ceiling:.1f}×",
                )
            )

            times = np.arange(big.size) * 0.01
            text = "time_s,value\n" + "\n".join(
                f"{t:.2f},{v:.6f}" for t, v in zip(times, big, strict=True)
            )
            csv_body = text.encode()
            as_csv = median_of(3, lambda _k: upload("text/csv", csv_body))
            results.append(
                (
                    "upload 1e6 samples (text/csv, time_s,value) + solve (s, median of 3)",
                    f"{as_csv:.3f}",
                    f"{len(csv_body) / 1e6:.0f} MB; raw float64 {binary:.3f} s → "
                    f"{as_csv / binary:.1f}×; BLOB write → {as_csv / ceiling:.1f}×",
                )
            )

            start = time.perf_counter()
            for _ in range(60):
                client.post(
                    "/api/v1/auth/token", data={"username": "student", "password": PASSWORD}
                ).raise_for_status()
            seconds = time.perf_counter() - start
            results.append(
                (
                    "60 logins, sequential (s)",
                    f"{seconds:.2f}",
                    f"{seconds / 60 * 1000:.0f} ms each (argon2id {ARGON2})",
                )
            )

            assignment_id, course_id = seed_dashboard(env, args.students)
            teacher = httpx.Client(base_url=url, timeout=120)
            page = teacher.get("/login")
            csrf = page.text.split('name="csrf_token" value="')[1].split('"')[0]
            teacher.post(
                "/login", data={"username": "teacher", "password": PASSWORD, "csrf_token": csrf}
            )
            path = f"/courses/{course_id}/assignments/{assignment_id}"
            teacher.get(path).raise_for_status()
            start = time.perf_counter()
            for _ in range(3):
                teacher.get(path).raise_for_status()
            seconds = (time.perf_counter() - start) / 3
            median = median_of(9, lambda _k: teacher.get(path).raise_for_status())
            results.append(
                (
                    f"dashboard of {args.students} submissions (s)",
                    f"{seconds:.3f}",
                    f"mean of 3; median of the next 9 {median:.3f} s; class charts included",
                )
            )
        finally:
            app.terminate()
            bare.terminate()
            app.wait(10)
            bare.wait(10)
    print(
        f"machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}"
    )
    width = max(len(r[0]) for r in results)
    for name, value, ceiling in results:
        print(f"{name:<{width}}  {value:>8}  {ceiling}")


if __name__ == "__main__":
    main()
