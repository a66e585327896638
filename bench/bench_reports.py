"""Time and memory of a PDF lab report: the worst discussion the form accepts against an
empty one, and the same report again from the PDF cache.

The worst case the probe found (issue 31) is 20,000 characters as 6,666 short paragraphs:
each one a block WeasyPrint lays out.  Each measurement runs in a fresh process and
reports its peak resident memory above the process's start (VmHWM after a reset).  The
baseline, in the same run, is the same session's report with no discussion.

    .venv/bin/python bench/bench_reports.py
"""

from __future__ import annotations

import multiprocessing
import os
import tempfile
import time

DISCUSSIONS = {
    "no discussion (baseline)": "",
    "20,000 characters, one paragraph": "north " * 3333,
    "6,666 paragraphs (the worst)": "n\n\n" * 6666,
}


def _rss_kib(field: str) -> int:
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith(field):
                return int(line.split()[1])
    return 0


def _measure(name: str, session_id: int, queue) -> None:
    from app.db import read_session, write_session
    from app.models import LabSession
    from app.reports.content import build_report
    from app.reports.discussion import save_discussion
    from app.reports.pdf import report_pdf
    from app.reports.pdf_cache import PdfCache, content_key

    with write_session() as db:
        save_discussion(db, db.get(LabSession, session_id), DISCUSSIONS[name])
    with read_session() as db:
        report = build_report(db, db.get(LabSession, session_id))
    report_pdf(build_report_empty(session_id), "en")  # fonts and imports warm
    with open("/proc/self/clear_refs", "w") as handle:
        handle.write("5")
    before = _rss_kib("VmRSS")
    start = time.perf_counter()
    content = report_pdf(report, "en")
    render_s = time.perf_counter() - start
    peak_mib = (_rss_kib("VmHWM") - before) / 1024
    cache = PdfCache(64 * 2**20)
    cache.put(content_key(report, "en"), content)
    start = time.perf_counter()
    with read_session() as db:  # a second request: gather the report, key it, look it up
        again = build_report(db, db.get(LabSession, session_id))
    assert cache.get(content_key(again, "en")) == content
    cached_s = time.perf_counter() - start
    paragraphs = report.discussion.count("\n\n") + 1 if report.discussion else 0
    queue.put((name, render_s, cached_s, peak_mib, len(content) / 1e3, paragraphs))


def build_report_empty(session_id: int):
    from app.db import read_session
    from app.models import LabSession
    from app.reports.content import build_report

    with read_session() as db:
        return build_report(db, db.get(LabSession, session_id))


def main() -> None:
    folder = tempfile.mkdtemp(prefix="gyrolab-bench-reports-")
    os.environ["GYROLAB_VAR_DIR"] = folder
    os.environ.pop("GYROLAB_DATABASE_URL", None)
    import numpy as np

    from app.accounts.service import create_user
    from app.db import write_session
    from app.lab.store import store_take
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
            values = 10 * np.cos(np.radians(angle + 30)) + rng.normal(0, 0.5, 12)
            store_take(db, session, part="heading", position=k, angle_deg=angle,
                       values=values, times=None, source="manual")  # fmt: skip
        session_id = session.id
    context = multiprocessing.get_context("spawn")
    print("one report, English; peak memory above the process's start")
    print(f"{'discussion':34} {'paras':>6} {'render':>8} {'ratio':>7} {'cached':>8} "
          f"{'peak RSS':>10} {'PDF':>8}")  # fmt: skip
    baseline = None
    for name in DISCUSSIONS:
        queue = context.Queue()
        process = context.Process(target=_measure, args=(name, session_id, queue))
        process.start()
        name, render_s, cached_s, peak_mib, kilobytes, paragraphs = queue.get()
        process.join()
        baseline = baseline or render_s
        print(f"{name:34} {paragraphs:6d} {render_s:7.2f}s {render_s / baseline:6.1f}× "
              f"{cached_s * 1e3:6.1f}ms {peak_mib:8.1f} MiB {kilobytes:6.0f} kB")  # fmt: skip


if __name__ == "__main__":
    main()
