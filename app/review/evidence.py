"""Data evidence for the teacher (``app.core.data_evidence``): whether each group's
readings look like the station's gyro made them, and whether two groups' readings match.

Only readings the students recorded themselves are checked (typed, pasted, uploaded, sent
by the bridge): the simulated gyro's recordings are made by the server.  The gyro is the
one the teacher characterised for the assignment, else the simulated gyro's preset --
whose output grid is then known too.  Students never see any of this."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from sqlmodel import Session, select

from app.core.data_copies import copy_keys
from app.core.data_evidence import off_grid, part_evidence, too_close
from app.core.exceptions import UserError
from app.core.output_grid import GridPart, class_step
from app.lab.copy_index import own_positions
from app.lab.planner import gyro_model
from app.lab.results import recorded_seconds
from app.lab.store import PARTS
from app.models import Assignment, EvidenceNote, InputMethod, LabSession, User, utcnow


@dataclass
class SessionEvidence:
    """One session's own findings, its parts' copy keys, and the parts it recorded."""

    findings: list[dict] = field(default_factory=list)
    keys: dict[str, list[str]] = field(default_factory=dict)  # part → copy keys
    recorded: set[str] = field(default_factory=set)  # parts with readings of its own
    # part → its first readings, for the class's output step (a real gyro's grid unknown)
    readings: dict[str, GridPart] = field(default_factory=dict)
    model_step: float = 0.0  # the station's gyro's rate step 3600·LSB·f (°/h), 0 if none
    # part → the median time its own positions average over (s), as the result's σ takes
    # it (:func:`app.lab.results.recorded_seconds`): the class accuracy's dwell
    seconds: dict[str, float] = field(default_factory=dict)


GRID_READINGS = 2000  # readings of each part kept for the class's output step


def session_evidence(assignment: Assignment, session: LabSession, data: dict) -> SessionEvidence:
    """The checks that need only this session's current readings (``data``: part →
    position → PositionData)."""
    noise, rate_hz, source = gyro_model(assignment, session.simulator_preset)
    out = SessionEvidence(model_step=3600.0 * noise.angle_lsb_deg * rate_hz)
    for part, positions in sorted(data.items()):
        own = own_positions(positions)
        if not own:
            continue
        values = [item.values for item in own]
        typed = any(item.take.source == InputMethod.manual for item in own)
        found = part_evidence(
            part,
            values,
            typed,
            noise,
            rate_hz,
            simulated=source == "preset",
            times=[item.times for item in own],
        )
        out.findings += [finding.to_json() for finding in found]
        out.keys[part] = copy_keys(values)
        out.seconds[part] = float(np.median([recorded_seconds(item, rate_hz) for item in own]))
        out.recorded.add(part)
        if source != "preset":  # the simulated gyro's grid is known: checked above
            out.readings[part] = GridPart.of(np.concatenate(values)[:GRID_READINGS])
    return out


def class_findings(rows, notes: dict | None = None, earlier: dict | None = None) -> None:
    """Complete each row's ``evidence``: its own findings, the parts whose readings match
    another group's, or readings submitted earlier (``earlier``: session → part → sources,
    ``app.review.earlier_copies``), and results far closer to the truth than their σ
    (parts the group recorded itself, from the attempt the teacher grades); each marked
    ``seen`` where a teacher has looked (``notes``: :func:`seen_notes`)."""
    notes, earlier = notes or {}, earlier or {}
    off_class = class_grid_findings(rows)
    owners: dict[tuple[str, str], set[str]] = {}
    for row in rows:
        if row.session is None or row.data_evidence is None:
            continue
        for part, keys in row.data_evidence.keys.items():
            for key in keys:
                owners.setdefault((part, key), set()).add(group_name(row))
    for row in rows:
        if row.session is None or row.data_evidence is None:
            continue
        found = list(row.data_evidence.findings) + off_class.get(row.session.id, [])
        for part, keys in sorted(row.data_evidence.keys.items()):
            others = set().union(*(owners[(part, key)] for key in keys)) - {group_name(row)}
            if others:
                found.append({"check": "copy", "part": part, "others": sorted(others)})
        for part, sources in sorted(earlier.get(row.session.id, {}).items()):
            found.append({"check": "copy_earlier", "part": part, "sources": sources})
        if row.latest is not None:
            found += [f.to_json() for f in result_findings(row)]
        for finding in found:
            seen = notes.get((row.session.id, finding["check"], finding["part"]))
            if seen is not None:
                finding["seen"] = seen
        row.evidence = found


def class_grid_findings(rows) -> dict[int, list[dict]]:
    """``off_class_grid`` for parts whose readings lie between the output steps that the
    rest of the class's readings keep to (``app.core.output_grid``), where the station's
    gyro is a real one whose grid is not known in advance."""
    parts = [
        (row.session.id, part, readings)
        for row in rows
        if row.session is not None and row.data_evidence is not None
        for part, readings in sorted(row.data_evidence.readings.items())
    ]
    model_step = max(
        (row.data_evidence.model_step for row in rows if row.data_evidence is not None),
        default=0.0,
    )
    step = class_step([readings for _sid, _part, readings in parts], model_step)
    found: dict[int, list[dict]] = {}
    if step is None:
        return found
    for session_id, part, readings in parts:
        for finding in off_grid(part, [readings.values], step):
            found.setdefault(session_id, []).append(
                {**finding.to_json(), "check": "off_class_grid"}
            )
    return found


def result_findings(row) -> list:
    """``too_close`` for each part the group recorded itself."""
    recorded = row.data_evidence.recorded
    found = []
    heading, latitude = row.results.get("heading"), row.results.get("latitude")
    if "heading" in recorded and heading:
        found += too_close("heading", row.check_error("heading"), heading.get("azimuth_sigma_deg"))
    if "latitude" in recorded and latitude:
        found += too_close(
            "latitude", latitude.get("latitude_error_deg"), latitude.get("latitude_sigma_deg")
        )
    return found


def group_name(row) -> str:
    """A group as the teacher knows it: its members' usernames (one, or partners)."""
    return "+".join(row.group) if row.group else row.student.username


def finding_text(finding: dict, _) -> str:
    """A finding in the teacher's words and language, with its numbers."""
    params = {k: v for k, v in finding.items() if k not in ("check", "part", "seen")}
    params["part"] = _(f"lab.part_short_{finding['part']}")
    if "share" in params:
        params["share"] = f"{100 * params['share']:.0f} %"
    if "p" in params:
        params["p"] = f"{params['p']:.1g}"
    if "sigma" in params:
        params["sigma"] = f"{params['sigma']:.3g}"
    for name in ("step", "expected"):
        if name in params:
            params[name] = f"{params[name]:.4g}"
    if "others" in params:
        params["others"] = ", ".join(params["others"])
    if "sources" in params:
        params["sources"] = "; ".join(source_text(source, _) for source in params["sources"])
    if "columns" in params:
        params["columns"] = ", ".join(
            _(f"lab.part_short_{c.split('-')[0]}") + c.split("-")[1] for c in params["columns"]
        )
    return _(f"evidence.{finding['check']}", **params)


def source_text(source: dict, _) -> str:
    """Where earlier readings were submitted: a group, its attempts, and the assignment
    (this one, another of the teacher's) or the uploaded archive."""
    attempts = ", ".join(str(n) for n in source.get("attempts", [])) or "—"
    if "archive" in source:
        return _(
            "evidence.source_archive",
            group=source["group"],
            attempts=attempts,
            archive=source["archive"],
        )
    if source.get("same"):
        return _("evidence.source_same", group=source["group"], attempts=attempts)
    return _(
        "evidence.source_other",
        group=source["group"],
        attempts=attempts,
        assignment=source["assignment"],
        course=source["course"],
    )


def once_per_finding(text: Callable[[dict], str]) -> Callable[[dict], str]:
    """``text`` of a finding, made once per distinct finding for one page: a class's
    findings repeat (the same check with the same numbers for many groups) and the
    dashboard shows two texts of each (≈ 15 µs a text; 1,200 in a class of 300 who typed
    their readings).  Findings with a list among their values are made every time."""
    made: dict[tuple, str] = {}

    def once(finding: dict) -> str:
        try:
            key = tuple(finding.items())
            return made[key]
        except KeyError:
            made[key] = value = text(finding)
            return value
        except TypeError:  # unhashable (other groups, sources): not kept
            return text(finding)

    return once


def badge_text(finding: dict, _) -> str:
    return f"{_('lab.part_short_' + finding['part'])}: {_('evidence.badge_' + finding['check'])}"


# --- a teacher has looked ---------------------------------------------------------------

CHECKS = (
    "scatter_low",
    "scatter_high",
    "smooth",
    "digits",
    "off_grid",
    "off_class_grid",
    "copy",
    "copy_earlier",
    "handout",
    "too_close",
    "time_order",
    "time_step",
)
MAX_NOTE = 2000


def mark_seen(
    db: Session,
    session: LabSession,
    findings: list[dict],
    teacher_id: int,
    check: str,
    part: str,
    note: str,
) -> EvidenceNote:
    """Mark one finding of ``session`` as seen by the teacher, with a note (a second mark
    replaces the note).  Only a finding the session has now (``findings``: its class row's
    ``evidence``) can be marked.  The finding itself stays: it is the readings' evidence."""
    if check not in CHECKS or part not in PARTS:
        raise UserError("evidence.bad_finding")
    if not any(f["check"] == check and f["part"] == part for f in findings):
        raise UserError("evidence.bad_finding")
    note = note.strip()
    if len(note) > MAX_NOTE:
        raise UserError("evidence.note_too_long", limit=MAX_NOTE)
    record = db.exec(
        select(EvidenceNote).where(
            EvidenceNote.session_id == session.id,
            EvidenceNote.check == check,
            EvidenceNote.part == part,
        )
    ).first() or EvidenceNote(session_id=session.id, check=check, part=part)
    record.note, record.teacher_id, record.seen_at = note, teacher_id, utcnow()
    db.add(record)
    return record


def seen_notes(db: Session, session_ids: list[int]) -> dict[tuple[int, str, str], dict]:
    """(session, check, part) → {"note", "seen_at", "by"} of the findings marked seen."""
    if not session_ids:
        return {}
    rows = db.exec(
        select(EvidenceNote, User.display_name)
        .join(User, User.id == EvidenceNote.teacher_id, isouter=True)
        .where(EvidenceNote.session_id.in_(session_ids))
    ).all()
    return {
        (note.session_id, note.check, note.part): {
            "note": note.note,
            "seen_at": note.seen_at,
            "by": name or "",
        }
        for note, name in rows
    }
