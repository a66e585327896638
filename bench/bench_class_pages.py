"""The teacher's pages for a class of 300 with everything the data evidence compares.

    .venv/bin/python bench/bench_class_pages.py [--students 300] [--backend sqlite|postgresql]

Seeds, straight into the database: this year's class of ``--students`` groups, each with
two parts typed from the teaching gyro as people round (bench_evidence.py's honest
typists: 12 readings a position, most at 2 decimals) and submitted, save ten still
recording; last year's class of the
same size under the same teacher (another course: its submitted attempts' copy keys are
what ``copy_earlier`` matches); an uploaded archive of as many groups; and planted among
this year's groups 5 copies of last year's readings and 5 of a classmate's, with offsets.
Then serves it (one worker on SQLite, 2 on PostgreSQL) and times, over HTTP, the pages a
teacher opens: the dashboard (class table with its evidence), the desk of one group, the
class board and its JSON, the submissions API and the class CSV -- each the first time after
the server starts (every group's data summarised), after one group saved new readings (its
summary alone redone), and warm (median of 9).  Checks that the planted copies are found.
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import httpx
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tests.e2e.conftest import running_server  # noqa: E402
from tests.pgserver import PostgresServer  # noqa: E402

PASSWORD = "bench-class-pass-1"
CSRF_RE = re.compile(r'name="csrf_token" value="([^"]+)"')
RECORDING = 10  # groups of this year still recording (their saves bump the data version)
PLANTED = 5  # copies of last year, and copies of a classmate

SEED = """
import sys
import numpy as np
from app.accounts.security import hash_password
from app.core.data_copies import copy_keys
from app.db import write_session
from app.lab.store import store_take
from app.lab.submissions import submit
from app.migrate import upgrade_to_head
from app.models import Assignment, Course, Enrollment, LabSession, User
from app.review.archives import ArchivedGroup, store_archive
from bench_evidence import honest_parts

upgrade_to_head()
students, password, recording, planted = (int(sys.argv[1]), sys.argv[2], int(sys.argv[3]),
                                           int(sys.argv[4]))
digest = hash_password(password)

def typed(student):
    return honest_parts('teaching-fog', student, 'typed', False)

def store(db, session, parts, offset=0.0):
    for part, columns in parts.items():
        for k, values in enumerate(columns, start=1):
            angle = -90.0 * (k - 1) if part == 'heading' else 90.0 * (k - 1)
            store_take(db, session, part=part, position=k, angle_deg=angle,
                       values=np.round(values + offset, 3), times=None, source='manual')

with write_session() as db:
    teacher = User(username='teacher', display_name='Teacher', role='teacher',
                   password_hash=digest)
    db.add(teacher); db.flush()
    classes = {}
    for year in ('last', 'this'):
        course = Course(name=f'Lab {year} year', teacher_id=teacher.id); db.add(course)
        db.flush()
        assignment = Assignment(course_id=course.id, title=f'North finding ({year} year)',
                                latitude_deg=39.93, earth_rate_deg_h=15.04,
                                true_heading_deg=10.8, allowed_methods='manual,csv')
        db.add(assignment); db.flush()
        classes[year] = (course, assignment)
    last_parts = []
    for year in ('last', 'this'):
        course, assignment = classes[year]
        made = []
        for i in range(students):
            user = User(username=f'{year[0]}{i:04d}', display_name=f'学生 {year} {i}',
                        role='student', password_hash=digest)
            db.add(user); db.flush()
            db.add(Enrollment(course_id=course.id, student_id=user.id))
            session = LabSession(owner_id=user.id, assignment_id=assignment.id,
                                 title=assignment.title, latitude_deg=39.93,
                                 earth_rate_deg_h=15.04)
            db.add(session); db.flush()
            if year == 'this' and i < planted:  # last year's readings, shifted
                parts = {p: [c + 0.37 for c in cols] for p, cols in last_parts[i].items()}
            elif year == 'this' and 0 <= i - (students - recording - planted) < planted:
                original = made[2 * planted + i - (students - recording - planted)][1]
                parts = {p: [c - 0.21 for c in cols] for p, cols in original.items()}
            else:
                parts = typed(i + (10_000 if year == 'last' else 0))
            store(db, session, parts)
            made.append((session, parts))
            if year == 'last':
                last_parts.append(parts)
            if not (year == 'this' and i >= students - recording):
                submit(db, session)
    groups = [ArchivedGroup(f'2024 group {g}', 1,
                            {p: copy_keys(cols) for p, cols in typed(20_000 + g).items()})
              for g in range(students)]
    store_archive(db, teacher.id, '2024 class.zip', groups)
    print(classes['this'][0].id, classes['this'][1].id)
"""


def seed(env: dict, students: int) -> tuple[int, int]:
    done = subprocess.run(
        [sys.executable, "-c", SEED, str(students), PASSWORD, str(RECORDING), str(PLANTED)],
        env=env,
        capture_output=True,
        text=True,
        cwd=ROOT / "bench",
    )
    if done.returncode:
        raise RuntimeError(done.stderr)
    course, assignment = (int(x) for x in done.stdout.split()[-2:])
    return course, assignment


def logged_in(url: str, username: str) -> httpx.Client:
    client = httpx.Client(base_url=url, timeout=300)
    token = CSRF_RE.search(client.get("/login").text).group(1)
    response = client.post(
        "/login", data={"username": username, "password": PASSWORD, "csrf_token": token}
    )
    assert response.status_code == 303, response.text[:300]
    return client


def timed(client: httpx.Client, path: str, **kwargs) -> float:
    start = time.perf_counter()
    response = client.get(path, **kwargs)
    seconds = time.perf_counter() - start
    response.raise_for_status()
    return seconds


def save_new_readings(student: httpx.Client, seed: int) -> None:
    """One recording group's heading typed again (the page's own JSON save)."""
    from bench_evidence import honest_parts  # bench/, the script's folder

    sessions = student.get("/api/v1/sessions").json()
    session_id = sessions[0]["id"]
    page = student.get(f"/lab/sessions/{session_id}").text
    token = CSRF_RE.search(page).group(1)
    heading = honest_parts("teaching-fog", seed, "typed", False)["heading"]
    columns = {str(k): [float(v) for v in values] for k, values in enumerate(heading, 1)}
    response = student.post(
        f"/lab/sessions/{session_id}/manual",
        json={"part": "heading", "unit": "deg/h", "columns": columns},
        headers={"X-CSRF-Token": token},
    )
    response.raise_for_status()


def measure(url: str, course: int, assignment: int, students: int) -> list[tuple[str, ...]]:
    teacher = logged_in(url, "teacher")
    api = {
        "Authorization": "Bearer "
        + teacher.post(
            "/api/v1/auth/token", data={"username": "teacher", "password": PASSWORD}
        ).json()["access_token"]
    }
    dashboard = f"/courses/{course}/assignments/{assignment}"
    first_row = teacher.get(f"/api/v1/assignments/{assignment}/submissions", headers=api)
    # the API's first call summarised the class; the dashboard's first view is timed on a
    # server restarted by the caller -- here, the first page the teacher opens
    rows = first_row.json()
    checks = {row["username"]: {f["check"] for f in row["evidence"]} for row in rows}
    # copies: of last year by groups 0-4; of groups 10-14 by the five before the recorders
    copiers = range(students - RECORDING - PLANTED, students - RECORDING)
    found_earlier = sum("copy_earlier" in checks[f"t{i:04d}"] for i in range(PLANTED))
    found_copies = sum("copy" in checks[f"t{i:04d}"] for i in copiers)
    involved = {*range(PLANTED), *range(2 * PLANTED, 3 * PLANTED), *copiers}
    honest = [u for u in checks if int(u[1:]) not in involved]
    flagged = sum(bool(checks[u] & {"copy", "copy_earlier"}) for u in honest)
    any_finding = sum(bool(checks[u]) for u in honest)
    desk_session = next(r["session_id"] for r in rows if r["username"] == "t0020")
    pages = {
        "dashboard": (dashboard, {}),
        "desk of one group": (f"/review/sessions/{desk_session}", {}),
        "class board": (f"{dashboard}/board", {}),
        "class board JSON": (f"{dashboard}/board.json", {}),
        "submissions API": (f"/api/v1/assignments/{assignment}/submissions", {"headers": api}),
        "class CSV": (f"{dashboard}/export.csv", {}),
        "class workbook (xlsx)": (f"{dashboard}/export.xlsx", {}),
    }
    recorders = [logged_in(url, f"t{i:04d}") for i in range(students - RECORDING, students)]
    out = []
    for name, (path, kwargs) in pages.items():
        warm = float(np.median([timed(teacher, path, **kwargs) for _ in range(9)]))
        changed = []
        for k, recorder in enumerate(recorders[:5]):
            save_new_readings(recorder, 30_000 + 10 * len(out) + k)
            changed.append(timed(teacher, path, **kwargs))
        out.append((name, f"{np.median(changed):.3f}", f"{warm:.3f}"))
    out.append(
        (
            "planted found",
            f"copies of last year {found_earlier}/{PLANTED}, of a classmate "
            f"{found_copies}/{PLANTED}",
            f"honest groups flagged as copies {flagged}/{len(honest)}, with any finding "
            f"{any_finding}/{len(honest)}",
        )
    )
    return out


def run(backend: str, students: int) -> None:
    with tempfile.TemporaryDirectory(prefix="gyrolab-class-") as var:
        var_dir = Path(var)
        pg = None
        database_url = f"sqlite:///{var_dir / 'gyrolab.db'}"
        serve_args = ["--no-demo", "--no-access-log"]
        if backend == "postgresql":
            pg = PostgresServer().start()
            database_url = pg.create_database("gyrolab_class")
            serve_args += ["--workers", "2"]
        try:
            env = {**os.environ, "GYROLAB_VAR_DIR": var, "GYROLAB_DATABASE_URL": database_url}
            started = time.perf_counter()
            course, assignment = seed(env, students)
            seeded = time.perf_counter() - started
            url = database_url if backend == "postgresql" else None
            with running_server(var_dir, *serve_args, database_url=url) as server:
                teacher = logged_in(server.url, "teacher")
                first = timed(teacher, f"/courses/{course}/assignments/{assignment}")
                rows = measure(server.url, course, assignment, students)
        finally:
            if pg is not None:
                pg.stop()
    print(f"\n### {backend}, {students} groups (seeded in {seeded:.0f} s)\n")
    print(f"dashboard, first view after the server started: {first:.3f} s\n")
    print("| page | after one group saved (median of 5), s | warm (median of 9), s |")
    print("|---|---:|---:|")
    for row in rows:
        print("| " + " | ".join(row) + " |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--students", type=int, default=300)
    parser.add_argument("--backend", choices=("sqlite", "postgresql", "both"), default="both")
    args = parser.parse_args()
    backends = ("sqlite", "postgresql") if args.backend == "both" else (args.backend,)
    for backend in backends:
        run(backend, args.students)


if __name__ == "__main__":
    main()
