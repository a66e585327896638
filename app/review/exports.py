"""The class's downloads for a teacher: the class table (CSV, or an Excel workbook whose
student numbers stay text and whose results are numbers) and every submitted attempt
(zip).  One function each, shared by the dashboard and the REST API.

The dashboard's downloads speak the teacher's language (column names, statuses, yes/no,
times in the course's zone) and are named after the course and assignment; the API's
class table keeps stable English column names and UTC times for scripts.
"""

from __future__ import annotations

import json
import math
import tempfile
import zipfile
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from datetime import UTC

from fastapi.responses import Response, StreamingResponse
from sqlmodel import Session

from app.core.jsonsafe import json_safe
from app.lab.attempts import comments_of, rubric_of, rubric_scores_of
from app.lab.exports import Selection, readings_csv, session_json
from app.lab.planner import assignment_plan
from app.models import Assignment, Attempt, Course
from app.review.accuracy import class_accuracy
from app.review.board import board_data
from app.review.evidence import finding_text
from app.review.service import StudentRow, class_rows
from app.web.exports import ZIP_BLOCK, attachment, csv_table, safe_name
from app.web.local_time import zone
from app.web.work_slots import held_while_streaming
from app.web.workbooks import XLSX_MEDIA_TYPE, xlsx_table

COLUMNS = (
    "username",
    "display_name",
    "partners",
    "status",
    "attempts",
    "submitted_at_utc",
    "late",
    "azimuth_deg",
    "azimuth_sigma_deg",
    "heading_error_deg",
    "latitude_deg",
    "latitude_error_percent",
    "earth_rate_deg_h",
    "earth_rate_error_percent",
    "auto_check",
    "points",
    "max_points",
    "letter_grade",
    "released",
    "feedback",
    "position_comments",
    "flags",
    "identical_data_with",
    "data_evidence",
)
# the columns a workbook holds as numbers (the rubric's criteria after them too)
NUMERIC_COLUMNS = frozenset(
    {
        "attempts",
        "azimuth_deg",
        "azimuth_sigma_deg",
        "heading_error_deg",
        "latitude_deg",
        "latitude_error_percent",
        "earth_rate_deg_h",
        "earth_rate_error_percent",
        "points",
        "max_points",
    }
)


def export_rows(
    rows: list[StudentRow],
    _: Callable[..., str] | None = None,
    zone_name: str | None = None,
    rubric: list[dict] | None = None,
) -> list[list]:
    """The assignment CSV: identifiers and lab partners, status, results, errors, grade,
    feedback, late flag, then one column per rubric criterion; in the reader's words when
    ``_`` is given (times then in ``zone_name``), else machine names."""

    def word(key: str, machine: str, **params) -> str:
        return _(key, **params) if _ else machine

    def part_name(key: str) -> str:  # "heading-2" -> "A2" (machine names: as it is)
        if not _:
            return key
        part, _sep, position = key.partition("-")
        return f"{word(f'lab.part_short_{part}', part)}{position}"

    shown_zone = zone(zone_name) if _ else UTC
    rubric = rubric or []
    header = [
        (_("export.submitted_at", zone=shown_zone.key) if _ else name)
        if name == "submitted_at_utc"
        else word(f"export.{name}", name)
        for name in COLUMNS
    ]
    header += [
        word(
            "export.rubric_column",
            f"rubric_{i}:{item['name']}",
            n=i,
            name=item["name"],
            points=f"{float(item.get('points', 0)):g}",
        )
        for i, item in enumerate(rubric, 1)
    ]
    members: dict[int, list[str]] = {}  # a shared session's students, in class-list order
    for row in rows:
        if row.session is not None:
            members.setdefault(row.session.id, []).append(row.student.username)
    out = [header]
    for row in rows:
        heading = row.results.get("heading") or {}
        latitude = row.results.get("latitude") or {}
        passed = None if row.check is None else row.check.passed
        submitted = row.submitted_at
        if submitted is not None:
            aware = submitted if submitted.tzinfo else submitted.replace(tzinfo=UTC)
            submitted = aware.astimezone(shown_zone)
        group = members.get(row.session.id, []) if row.session is not None else []
        comments = comments_of(row.latest)
        scores = rubric_scores_of(row.latest)

        out.append(
            [
                row.student.username,
                row.student.display_name,
                ";".join(name for name in group if name != row.student.username),
                word(f"status.{row.status}", row.status),
                len(row.attempts),
                submitted.strftime("%Y-%m-%d %H:%M:%S") if submitted else "",
                word("export.yes", "yes") if row.late else word("export.no", "no"),
                _num(heading.get("azimuth_deg")),
                _num(heading.get("azimuth_sigma_deg")),
                _num(row.check_error("heading")),
                _num(latitude.get("latitude_deg")),
                _num(row.check_error("latitude")),
                _num(latitude.get("earth_rate_deg_h")),
                _num(row.check_error("earth_rate")),
                ""
                if passed is None
                else (word("review.pass", "pass") if passed else word("review.fail", "fail")),
                _num(row.points),
                f"{row.max_points:g}",
                row.letter,
                word("export.yes", "yes") if row.released else word("export.no", "no"),
                row.latest.feedback if row.latest else "",
                "; ".join(f"{part_name(k)}: {v}" for k, v in sorted(comments.items())),
                ";".join(
                    sorted({word(f"review.flag_{name}", name) for name in flag_names(row.flags)})
                ),
                ";".join(row.duplicate_of),
                " | ".join(finding_text(f, _) for f in row.evidence)
                if _
                else ";".join(f"{f['part']}:{f['check']}" for f in row.evidence),
                *(_score(scores.get(str(i))) for i in range(len(rubric))),
            ]
        )
    return out


def flag_names(flags: list[dict]) -> set[str]:
    """The flags' short names ("spikes", "unit_slip"): their keys' last part."""
    return {flag["key"].split(".")[-1] for flag in flags}


def _score(value: float | None) -> str:
    return "" if value is None else f"{value:g}"


def _num(value: float | None) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return ""
    return f"{value:.4f}"


def class_table_response(
    db: Session,
    assignment: Assignment,
    course: Course | None = None,
    _: Callable[..., str] | None = None,
) -> StreamingResponse:
    """The class table as CSV (UTF-8 with BOM, cells safe to open in a spreadsheet); with
    ``course`` and ``_``, in the teacher's language and named after course and assignment."""
    rows = export_rows(
        class_rows(db, assignment), _, course.timezone if course else None, rubric_of(assignment)
    )
    names = [course.name, assignment.title] if course else [f"assignment-{assignment.id}"]
    return StreamingResponse(
        csv_table(rows),
        media_type="text/csv; charset=utf-8",
        headers={"Content-Disposition": attachment(names, "csv")},
    )


def class_table_xlsx_response(
    db: Session,
    assignment: Assignment,
    course: Course | None = None,
    _: Callable[..., str] | None = None,
) -> Response:
    """The class table as an Excel workbook: the same rows as the CSV
    (:func:`class_table_response`), text kept as text -- a student number such as
    202301010101 is not turned into 2.02301E+11, nothing is ever a formula -- and the
    results, points and rubric scores as numbers."""
    rubric = rubric_of(assignment)
    rows = export_rows(class_rows(db, assignment), _, course.timezone if course else None, rubric)
    names = [course.name, assignment.title] if course else [f"assignment-{assignment.id}"]
    return Response(
        class_workbook(rows, len(rubric), _),
        media_type=XLSX_MEDIA_TYPE,
        headers={"Content-Disposition": attachment(names, "xlsx")},
    )


def class_workbook(rows: list[list], rubric_items: int, _: Callable[..., str] | None) -> bytes:
    """:func:`export_rows`' table as a workbook: results, points and rubric scores as
    numbers, everything else as text, the sheet named in the reader's language."""
    numeric = [i for i, name in enumerate(COLUMNS) if name in NUMERIC_COLUMNS]
    numeric += range(len(COLUMNS), len(COLUMNS) + rubric_items)
    return xlsx_table(rows, numeric, _("export.sheet_name") if _ else "class")


def class_zip_response(
    db: Session, assignment: Assignment, course: Course, _: Callable[..., str], requester_id: int
) -> StreamingResponse:
    """The class table plus every submitted attempt's own data (CSV and JSON with its
    results): what the students submitted, never what they changed afterwards."""
    rows = class_rows(db, assignment)
    work = [
        SubmittedWork(row.student.username, row.session.id, list(row.attempts))
        for row in rows
        if row.session is not None and row.attempts
    ]
    summaries = {  # the class's measurement as a whole, as the board and the planner show it
        "class-board.json": json_safe(board_data(db, assignment, rows, names=True)),
        "class-accuracy.json": json_safe(class_accuracy(assignment, rows)),
        "accuracy-plan.json": json_safe(assignment_plan(assignment).to_json()),
    }
    rubric = rubric_of(assignment)
    table = export_rows(rows, _, course.timezone, rubric)
    summaries["class.xlsx"] = class_workbook(table, len(rubric), _)
    blocks = assignment_zip(table, work, summaries)
    return StreamingResponse(
        held_while_streaming("exports", requester_id, blocks),
        media_type="application/zip",
        headers={"Content-Disposition": attachment([course.name, assignment.title], "zip")},
    )


# --- the class's zip ------------------------------------------------------------------------


@dataclass
class SubmittedWork:
    """One student's submitted work in an assignment zip."""

    username: str
    session_id: int
    attempts: list[Attempt]


def attempts_summary(attempts: list[Attempt]) -> list[dict]:
    return [
        {
            "number": a.number,
            "submitted_at": a.submitted_at.isoformat(),
            "late": a.late,
            "results": json.loads(a.results_json),
        }
        for a in attempts
    ]


def assignment_zip(
    class_table: list[list], work: list[SubmittedWork], summaries: dict | None = None
) -> Iterator[bytes]:
    """``class.csv``, the class-wide ``summaries`` (name → JSON-able: the board, the
    accuracy against the planner, the plan; or bytes as they are: the class table as a
    workbook) and, per student, every submitted attempt's own data (CSV and JSON): built in
    a temporary file (spilled to disk past 8 MB), then sent block by block."""
    with tempfile.SpooledTemporaryFile(max_size=8 * 1024 * 1024) as spool:
        with zipfile.ZipFile(spool, "w", zipfile.ZIP_DEFLATED, compresslevel=1) as archive:
            _write_text(archive, "class.csv", csv_table(class_table))
            for name, content in (summaries or {}).items():
                if isinstance(content, bytes):
                    archive.writestr(name, content)
                else:
                    text = json.dumps(content, ensure_ascii=False, indent=1)
                    _write_text(archive, name, [text])
            for item in work:
                stem = safe_name(item.username)
                summary = attempts_summary(item.attempts)
                for attempt in item.attempts:
                    selection = Selection(item.session_id, attempt.id)
                    name = f"{stem}/attempt-{attempt.number}"
                    _write_text(archive, f"{name}.csv", readings_csv(selection))
                    _write_text(archive, f"{name}.json", session_json(selection, summary))
        spool.seek(0)
        while block := spool.read(ZIP_BLOCK):
            yield block


def _write_text(archive: zipfile.ZipFile, name: str, pieces: Iterable[str]) -> None:
    with archive.open(name, "w", force_zip64=True) as member:
        for piece in pieces:
            member.write(piece.encode("utf-8"))
