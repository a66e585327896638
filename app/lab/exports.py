"""A lab session's downloads: its readings as CSV and the session as JSON, for its
current takes or one attempt's own (``Selection``), safe to open in a spreadsheet
(``app.web.exports``).

Memory: readings are read and written one stored chunk (65,536 samples) at a time, so an
export of 4 × 1e6 samples costs a few MB whatever its size (``bench/bench_exports.py``).
The generators open their own read session: they run after the handler has returned.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Iterator
from dataclasses import dataclass

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
from app.web.exports import (
    BOM,
    comment_line,
    neutralise,
)


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
