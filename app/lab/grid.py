"""The readings a student already saved, as the typed grid shows them for editing.

A correction is typed over the saved numbers and saved as a new take of that position; the
old take stays in the session's history (re-recording supersedes, never deletes).
"""

from __future__ import annotations

from sqlmodel import Session

from app.core.units import DEG_PER_HOUR, from_deg_per_hour
from app.lab.store import current_takes, load_samples
from app.models import LabSession

# A position with more readings than this (a long simulator or device run) is not put in
# the grid: nobody edits 60,000 numbers by hand, and the page would carry megabytes.
GRID_LIMIT = 2000
SIGNIFICANT_DIGITS = 12  # enough for any typed reading; hides the unit round trip's 1e-16


def grid_readings(db: Session, session: LabSession, part: str) -> dict:
    """The current readings of one part, position by position, in one unit.

    Returns ``{"unit": u, "positions": {"k": {"n", "source", "values"}}}`` where ``values``
    is the list of used readings (after any trimmed transient) in ``u``, or ``None`` when
    the position has more than :data:`GRID_LIMIT`.  ``u`` is the unit the readings were
    saved in when all positions share one, else °/h.
    """
    takes = [take for take in current_takes(db, session.id) if take.part == part]
    units = {take.unit for take in takes}
    unit = units.pop() if len(units) == 1 else DEG_PER_HOUR
    positions: dict[str, dict] = {}
    for take in takes:
        used = take.n_samples - take.trim_start
        entry: dict = {"n": used, "source": take.source, "values": None}
        if used <= GRID_LIMIT:
            values, _ = load_samples(db, take)
            shown = from_deg_per_hour(values[take.trim_start :], unit)
            entry["values"] = [float(f"{v:.{SIGNIFICANT_DIGITS}g}") for v in shown]
        positions[str(take.position)] = entry
    return {"unit": unit, "positions": positions}
