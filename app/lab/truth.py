"""A session's secret truth and the auto-check of a result against it.

Heading truth: the session's secret simulator azimuth when every heading position came
from the simulated gyro; otherwise the assignment's known bench azimuth, if the teacher
gave one.  Latitude and Earth-rate truth: the assignment's station values.  Whether the
student may see it follows the assignment's reveal rule (``truth_visible``).
"""

from __future__ import annotations

import random
from dataclasses import dataclass, field

from sqlmodel import Session

from app.core.handout_terms import percent_error
from app.core.sinusoid import wrap180
from app.lab.store import current_takes
from app.models import (
    Assignment,
    InputMethod,
    LabSession,
    RevealTruth,
    SessionStatus,
    Take,
)


def draw_truth(assignment: Assignment, session: LabSession, rng: random.Random) -> None:
    """Give a new assignment session its secret truth from the teacher's ranges."""
    low, high = assignment.azimuth_min_deg, assignment.azimuth_max_deg
    span = (high - low) % 360.0 or (360.0 if high != low else 0.0)
    session.sim_azimuth_deg = (low + rng.random() * span) % 360.0
    if assignment.turn_on_bias_max_deg_h is not None:
        limit = abs(assignment.turn_on_bias_max_deg_h)
        session.sim_turn_on_bias_deg_h = rng.uniform(-limit, limit)
    session.sim_indexing_sigma_arcsec = assignment.indexing_sigma_arcsec
    if assignment.table_tilt_max_deg is not None:
        limit = abs(assignment.table_tilt_max_deg)
        session.sim_pitch_deg = rng.uniform(-limit, limit)
        session.sim_roll_deg = rng.uniform(-limit, limit)
    if assignment.misalignment_max_deg is not None:
        limit = abs(assignment.misalignment_max_deg)
        session.sim_misalign_h_deg = rng.uniform(-limit, limit)
        session.sim_misalign_v_deg = rng.uniform(-limit, limit)


@dataclass
class Truth:
    azimuth_deg: float | None
    latitude_deg: float
    earth_rate_deg_h: float
    turn_on_bias_deg_h: float | None
    azimuth_source: str | None  # "simulator" | "bench" | None


def session_truth(
    db: Session,
    session: LabSession,
    assignment: Assignment | None,
    takes: list[Take] | None = None,
) -> Truth:
    """The session's truth; ``takes`` (its current takes) saves a query when known."""
    from app.lab.sim import turn_on_bias

    if takes is None:
        takes = current_takes(db, session.id)
    heading_sources = {t.source for t in takes if t.part == "heading"}
    azimuth, source = None, None
    if heading_sources == {InputMethod.simulator}:
        azimuth, source = session.sim_azimuth_deg, "simulator"
    elif assignment is not None and assignment.true_heading_deg is not None:
        azimuth, source = assignment.true_heading_deg, "bench"
    uses_simulator = any(t.source == InputMethod.simulator for t in takes)
    return Truth(
        azimuth,
        session.latitude_deg,
        session.earth_rate_deg_h,
        turn_on_bias(session) if uses_simulator else None,
        source,
    )


@dataclass
class Check:
    name: str  # heading | latitude | earth_rate
    error: float | None  # degrees for heading, percent otherwise
    tolerance: float
    passed: bool | None  # None: cannot be checked


@dataclass
class AutoCheck:
    checks: list[Check] = field(default_factory=list)

    @property
    def passed(self) -> bool | None:
        decided = [c.passed for c in self.checks if c.passed is not None]
        if not decided:
            return None
        return all(decided)


def heading_error(azimuth_deg: float | None, truth_deg: float | None) -> float | None:
    """Estimate − truth wrapped to (−180°, 180°]: 359.5° against 0.5° is −1°, not 359°."""
    if azimuth_deg is None or truth_deg is None:
        return None
    return wrap180(azimuth_deg - truth_deg)


def auto_check(results: dict, truth: Truth, assignment: Assignment) -> AutoCheck:
    """Compare a results dict (the solve JSON of each part) with the truth."""
    heading = results.get("heading") or {}
    latitude = results.get("latitude") or {}
    checks = []
    error = heading_error(heading.get("azimuth_deg"), truth.azimuth_deg)
    checks.append(
        Check(
            "heading",
            error,
            assignment.tolerance_heading_deg,
            None if error is None else abs(error) <= assignment.tolerance_heading_deg,
        )
    )
    for name, key, true_value, tolerance in (
        ("latitude", "latitude_deg", truth.latitude_deg, assignment.tolerance_latitude_pct),
        (
            "earth_rate",
            "earth_rate_deg_h",
            truth.earth_rate_deg_h,
            assignment.tolerance_earth_rate_pct,
        ),
    ):
        measured = latitude.get(key)
        pct = None if measured is None else percent_error(measured, true_value)
        checks.append(Check(name, pct, tolerance, None if pct is None else pct <= tolerance))
    return AutoCheck(checks)


def truth_visible(session: LabSession, assignment: Assignment | None, attempts: int) -> bool:
    """May the student see their secret truth now?"""
    if assignment is None:
        return attempts > 0  # practice: after submitting
    if assignment.reveal_truth == RevealTruth.after_submission:
        return attempts > 0
    if assignment.reveal_truth == RevealTruth.after_grading:
        return session.status == SessionStatus.graded
    return False
