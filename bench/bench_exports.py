"""Memory and time of the streamed exports on a 4 × 1e6-sample session.

Each measurement runs in a fresh process and reports its peak resident memory above what
the process held before it started (VmHWM after resetting it), so one export's memory
never hides another's.  The baseline, measured in the same run, reads every sample BLOB
of the session and throws it away: the least any export must do.

    .venv/bin/python bench/bench_exports.py [--samples 1000000]
"""

from __future__ import annotations

import argparse
import multiprocessing
import os
import tempfile
import time


def _rss_kib(field: str) -> int:
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith(field):
                return int(line.split()[1])
    return 0


def _reset_peak() -> None:
    with open("/proc/self/clear_refs", "w") as handle:  # Linux: VmHWM := VmRSS
        handle.write("5")


def _measure(kind: str, session_id: int, attempt_id: int, queue) -> None:
    from sqlmodel import select

    from app.db import read_session
    from app.lab.exports import Selection, readings_csv, session_json
    from app.models import Attempt, SampleChunk
    from app.review.exports import SubmittedWork, assignment_zip

    with read_session() as db:  # warm imports and the connection outside the measurement
        attempt = db.get(Attempt, attempt_id)
    _reset_peak()
    before = _rss_kib("VmRSS")
    start = time.perf_counter()
    size = 0
    if kind == "baseline: read every BLOB":
        with read_session() as db:
            for blob in db.exec(
                select(SampleChunk.values).execution_options(yield_per=4)
            ).yield_per(4):
                size += len(blob)
    elif kind == "export.csv (streamed)":
        size = sum(len(piece.encode()) for piece in readings_csv(Selection(session_id)))
    elif kind == "export.json (streamed)":
        size = sum(len(piece.encode()) for piece in session_json(Selection(session_id)))
    else:
        work = [SubmittedWork("s1", session_id, [attempt])]
        size = sum(len(block) for block in assignment_zip([["username"], ["s1"]], work))
    seconds = time.perf_counter() - start
    queue.put((kind, seconds, (_rss_kib("VmHWM") - before) / 1024, size / 1e6))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=1_000_000)
    args = parser.parse_args()
    folder = tempfile.mkdtemp(prefix="gyrolab-bench-exports-")
    os.environ["GYROLAB_VAR_DIR"] = folder
    os.environ.pop("GYROLAB_DATABASE_URL", None)

    import numpy as np

    from app.accounts.service import create_user
    from app.db import write_session
    from app.lab.store import store_take
    from app.lab.submissions import submit
    from app.migrate import upgrade_to_head
    from app.models import LabSession, Role

    upgrade_to_head()
    rng = np.random.default_rng(1)
    with write_session() as db:
        user = create_user(
            db, username="s1", display_name="S", role=Role.student, password="x" * 12
        )
        session = LabSession(owner_id=user.id, title="bench", latitude_deg=40.0)
        db.add(session)
        db.flush()
        for k, angle in enumerate((0, -90, -180, -270), start=1):
            values = 10 * np.cos(np.radians(angle + 30)) + rng.normal(0, 0.5, args.samples)
            store_take(
                db,
                session,
                part="heading",
                position=k,
                angle_deg=angle,
                values=values,
                times=None,
                source="api",
            )
        attempt = submit(db, session)
        db.flush()
        session_id, attempt_id = session.id, attempt.id

    context = multiprocessing.get_context("spawn")
    print(f"4 positions × {args.samples:,} samples; peak memory above the process's start")
    print(f"{'measurement':32} {'time':>8} {'peak RSS':>10} {'output':>10}")
    baseline = None
    for kind in (
        "baseline: read every BLOB",
        "export.csv (streamed)",
        "export.json (streamed)",
        "assignment zip (1 student)",
    ):
        queue = context.Queue()
        process = context.Process(target=_measure, args=(kind, session_id, attempt_id, queue))
        process.start()
        name, seconds, peak_mib, megabytes = queue.get()
        process.join()
        baseline = baseline or seconds
        ratio = f"{seconds / baseline:5.1f}×"
        print(f"{name:32} {seconds:7.2f}s {peak_mib:8.1f} MiB {megabytes:8.1f} MB  {ratio}")


if __name__ == "__main__":
    main()
