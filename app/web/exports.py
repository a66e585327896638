"""Every file the app writes for download: safe to open in a spreadsheet, and streamed.

Safety (OWASP "CSV injection"): a text cell that a spreadsheet would run as a formula --
one starting with ``= + - @``, a tab or a carriage return, and not a plain number -- gets
a leading apostrophe; comment lines never carry a raw line break.

Memory: readings are read and written one stored chunk (65,536 samples) at a time, so an
export of 4 × 1e6 samples costs a few MB whatever its size (``bench/bench_exports.py``).
The generators open their own read session: they run after the handler has returned.
"""

from __future__ import annotations

import csv
import io
import json
import math
import re
import tempfile
import zipfile
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from urllib.parse import quote

import numpy as np
from sqlmodel import Session, func, select

from app import __version__
from app.core.jsonsafe import json_safe
from app.db import read_session
from app.lab.results import (
    PartResult,
    PositionData,
    results_json,
    solve_part,
    station_noise_for,
)
from app.lab.samples import unpack
from app.lab.store import PARTS
from app.lab.submissions import export_metadata
from app.models import Attempt, LabSession, SampleChunk, Take

FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r")
ZIP_BLOCK = 64 * 1024
BOM = "\ufeff"


def neutralise(text: str) -> str:
    """A text cell as a spreadsheet will show it, never run it: formulas get an apostrophe."""
    if not text.startswith(FORMULA_STARTS) and not text.lstrip().startswith(FORMULA_STARTS):
        return text
    try:
        float(text)
    except ValueError:
        return "'" + text
    return text  # a plain number such as -10.75 stays a number


def one_line(text: str) -> str:
    """Line breaks (and other control characters) become spaces."""
    return "".join(" " if ord(ch) < 32 or ch in "\u2028\u2029\x85" else ch for ch in text)


def csv_line(cells: Iterable[object]) -> str:
    """One CSV line; text cells neutralised and kept on one line (a name needs no break)."""
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="\n").writerow(
        [one_line(neutralise(cell)) if isinstance(cell, str) else cell for cell in cells]
    )
    return buffer.getvalue()


def comment_line(text: str) -> str:
    """A ``# ...`` line: line breaks and other control characters become spaces."""
    return "# " + one_line(text) + "\n"


def csv_table(rows: Iterable[list]) -> Iterator[str]:
    """A whole table (header row first) as CSV lines, UTF-8 BOM first (Excel and Chinese)."""
    yield BOM
    for row in rows:
        yield csv_line(row)


def credentials_data_url(credentials) -> str:
    """A ``data:`` URL holding one-time passwords as CSV, so they are downloaded without
    being stored anywhere (``credentials``: items with username, display_name, password)."""
    rows = [["username", "display_name", "initial_password"]]
    rows += [[item.username, item.display_name, item.password] for item in credentials]
    return "data:text/csv;charset=utf-8," + quote("".join(csv_table(rows)))


# --- the takes of an export -----------------------------------------------------------------


@dataclass(frozen=True)
class Selection:
    """Which takes an export holds: a session's current ones, or an attempt's own."""

    session_id: int
    attempt_id: int | None = None

    def takes(self, db: Session) -> list[Take]:
        if self.attempt_id is None:
            statement = select(Take).where(
                Take.session_id == self.session_id, Take.superseded_at.is_(None)
            )
        else:
            attempt = db.get(Attempt, self.attempt_id)
            ids = [int(i) for i in attempt.take_ids.split(",") if i]
            statement = select(Take).where(Take.id.in_(ids), Take.session_id == self.session_id)
        return sorted(db.exec(statement).all(), key=lambda t: (PARTS.index(t.part), t.position))


Block = tuple[np.ndarray, np.ndarray | None, np.ndarray | None]


def take_blocks(db: Session, take: Take) -> Iterator[Block]:
    """A take's samples block by block (values °/h, times s or None, temperatures °C or
    None), in order."""
    rows = db.exec(
        select(SampleChunk.values, SampleChunk.times, SampleChunk.temperatures)
        .where(SampleChunk.take_id == take.id)
        .order_by(SampleChunk.seq)
        .execution_options(yield_per=4)
    )
    for values, times, temperatures in rows:
        yield (
            unpack(values),
            None if times is None else unpack(times),
            None if temperatures is None else unpack(temperatures),
        )


def solve_takes(db: Session, session: LabSession, takes: list[Take]) -> dict[str, PartResult]:
    """Both parts solved from exactly these takes (an attempt's, or the current ones),
    with their samples, worked steps and flags -- as the session page solves them."""
    data: dict[str, dict[int, PositionData]] = {part: {} for part in PARTS}
    for take in takes:
        blocks = list(take_blocks(db, take))
        values = np.concatenate([v for v, _, _ in blocks]) if blocks else np.empty(0)
        times = temperatures = None
        if blocks and all(t is not None for _, t, _ in blocks):
            times = np.concatenate([t for _, t, _ in blocks])
        if blocks and all(c is not None for _, _, c in blocks):
            temperatures = np.concatenate([c for _, _, c in blocks])
        data[take.part][take.position] = PositionData.of(take, values, times, temperatures)
    station = station_noise_for(db, session)
    return {part: solve_part(session, part, data[part], station) for part in PARTS}


def _results(db: Session, session: LabSession, selection: Selection, takes: list[Take]) -> dict:
    if selection.attempt_id is not None:
        return json.loads(db.get(Attempt, selection.attempt_id).results_json)
    results = solve_takes(db, session, takes)
    return json_safe(results_json(results))


# --- one session ----------------------------------------------------------------------------


def readings_csv(selection: Selection) -> Iterator[str]:
    """``part,position,angle_deg,source,time_s,value`` (°/h) for every sample, streamed,
    with ``temperature_c`` (empty where not reported) when any position has temperatures."""
    with read_session() as db:
        session = db.get(LabSession, selection.session_id)
        yield BOM
        yield comment_line(f"GyroLab {__version__}; session {session.id}: {session.title}")
        if selection.attempt_id is not None:
            attempt = db.get(Attempt, selection.attempt_id)
            yield comment_line(
                f"submitted attempt {attempt.number} of {attempt.submitted_at.isoformat()}"
            )
        yield comment_line(
            f"station latitude {session.latitude_deg} deg, Earth rate "
            f"{session.earth_rate_deg_h} deg/h; heading rotation {session.heading_rotation}; "
            "values in deg/h"
        )
        takes = selection.takes(db)
        for take in takes:
            if take.trim_start:
                yield comment_line(
                    f"{take.part} position {take.position}: the first {take.trim_start} "
                    "readings (the transient after turning) are trimmed: not used, not listed"
                )
        with_temperatures = any(take_has(db, take, SampleChunk.temperatures) for take in takes)
        yield "part,position,angle_deg,source,time_s,value"
        yield ",temperature_c\n" if with_temperatures else "\n"
        for take in takes:
            prefix = f"{take.part},{take.position},{take.angle_deg:g},{neutralise(take.source)},"
            index = 0
            skip = take.trim_start or 0
            for values, times, temperatures in take_blocks(db, take):
                stamps = times if times is not None else np.arange(index, index + values.size)
                index += values.size
                start = min(max(skip - (index - values.size), 0), values.size)
                rows = zip(stamps[start:].tolist(), values[start:].tolist(), strict=True)
                if not with_temperatures:
                    yield "".join(f"{prefix}{t:.3f},{v:.6f}\n" for t, v in rows)
                    continue
                cells = (
                    [f"{c:.2f}" for c in temperatures[start:].tolist()]
                    if temperatures is not None
                    else [""] * (values.size - start)
                )
                yield "".join(
                    f"{prefix}{t:.3f},{v:.6f},{c}\n" for (t, v), c in zip(rows, cells, strict=True)
                )


def _number_list(arrays: Iterable[np.ndarray]) -> Iterator[str]:
    first = True
    for array in arrays:
        if not array.size:
            continue
        text = ",".join(repr(x) if math.isfinite(x) else "null" for x in array.tolist())
        yield text if first else "," + text
        first = False


def session_json(selection: Selection, attempts: list[dict] | None = None) -> Iterator[str]:
    """``{"metadata", "positions": [... "values_deg_h", "times_s", "temperatures_c"],
    "results"[, "attempts"]}``
    written piece by piece (the samples never sit in memory as one list)."""
    with read_session() as db:
        session = db.get(LabSession, selection.session_id)
        takes = selection.takes(db)
        metadata = export_metadata(session)
        if selection.attempt_id is not None:
            attempt = db.get(Attempt, selection.attempt_id)
            metadata["attempt"] = {
                "number": attempt.number,
                "submitted_at": attempt.submitted_at.isoformat(),
                "late": attempt.late,
            }
        yield '{"metadata": ' + json.dumps(metadata, ensure_ascii=False) + ', "positions": ['
        for number, take in enumerate(takes):
            head = {
                "part": take.part,
                "position": take.position,
                "angle_deg": take.angle_deg,
                "source": take.source,
                "recorded_at": take.created_at.isoformat(),
                "trim_start": take.trim_start,  # the first readings, kept but not used
            }
            yield ("" if number == 0 else ", ") + json.dumps(head)[:-1] + ', "values_deg_h": ['
            yield from _number_list(values for values, _, _ in take_blocks(db, take))
            yield "]"
            for name, column, index in (
                ("times_s", SampleChunk.times, 1),
                ("temperatures_c", SampleChunk.temperatures, 2),
            ):
                if take_has(db, take, column):
                    yield f', "{name}": ['
                    yield from _number_list(block[index] for block in take_blocks(db, take))
                    yield "]"
                else:
                    yield f', "{name}": null'
            yield "}"
        yield '], "results": ' + json.dumps(_results(db, session, selection, takes))
        if attempts is not None:
            yield ', "attempts": ' + json.dumps(attempts, ensure_ascii=False)
        yield "}\n"


def take_has(db: Session, take: Take, column) -> bool:
    """Whether every stored block of the take carries ``column`` (times, temperatures)."""
    missing = db.exec(
        select(func.count())
        .select_from(SampleChunk)
        .where(SampleChunk.take_id == take.id, column.is_(None))
    ).one()
    return missing == 0


# --- a class ----------------------------------------------------------------------------------


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


def assignment_zip(class_table: list[list], work: list[SubmittedWork]) -> Iterator[bytes]:
    """``class.csv`` and, per student, every submitted attempt's own data (CSV and JSON):
    built in a temporary file (spilled to disk past 8 MB), then sent block by block."""
    with tempfile.SpooledTemporaryFile(max_size=8 * 1024 * 1024) as spool:
        with zipfile.ZipFile(spool, "w", zipfile.ZIP_DEFLATED, compresslevel=1) as archive:
            _write_text(archive, "class.csv", csv_table(class_table))
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


FILENAME_UNSAFE = re.compile(r'[\x00-\x1f\x7f/\\:*?"<>|;,%]+')


def attachment(parts: list[str], extension: str) -> str:
    """A Content-Disposition naming the download after its contents (course, assignment,
    student…): an ASCII ``filename`` for old clients and the UTF-8 ``filename*`` (RFC 6266
    / 5987) that browsers use, so "惯导实验_寻北_s1.csv" survives."""
    cleaned = [
        re.sub(r"\s+", "-", FILENAME_UNSAFE.sub("-", part).strip()).strip("-.") for part in parts
    ]
    stem = "_".join(part for part in cleaned if part)[:120] or "gyrolab"
    ascii_stem = "".join(
        ch if ch.isascii() and (ch.isalnum() or ch in "_.-") else "_" for ch in stem
    )
    ascii_stem = re.sub(r"-*_[-_]*", "_", ascii_stem).strip("_.-") or "gyrolab"
    return (
        f'attachment; filename="{ascii_stem}.{extension}"; '
        f"filename*=UTF-8''{quote(stem)}.{extension}"
    )


def safe_name(text: str) -> str:
    """A file or folder name from a username (which is already [A-Za-z0-9_.-])."""
    cleaned = "".join(ch if ch.isalnum() or ch in "_.-" else "_" for ch in text).lstrip(".")
    return cleaned or "student"
