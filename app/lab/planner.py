"""The accuracy planner of a session: what 1σ its station's gyro gives for each dwell per
position and order, before anything is recorded (``app.core.accuracy_plan``).

The gyro is the one the teacher characterised for the assignment (an uploaded Allan
record) when there is one, else the session's simulated gyro's preset -- the same noise
model the results use."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

from sqlmodel import Session

from app.core.accuracy_plan import AccuracyPlan, accuracy_plan
from app.core.noise_model import GyroNoise
from app.core.presets import PRESETS
from app.courses.characterisation import station_noise
from app.models import Assignment, LabSession

FIRST_DWELL_S = 60.0  # "with 60 s per position expect …"


@dataclass(frozen=True)
class SessionPlan:
    plan: AccuracyPlan
    source: str  # "station" (the characterised gyro) | "preset" (the simulated gyro's)
    preset_name: str
    dwell_s: float  # the dwell the sentence quotes

    def to_json(self) -> dict:
        return {
            **self.plan.to_json(),
            "source": self.source,
            "preset": self.preset_name if self.source == "preset" else None,
            "quoted_dwell_s": self.dwell_s,
        }


def gyro_model(assignment: Assignment | None, preset_name: str) -> tuple[GyroNoise, float, str]:
    """(noise, sample rate, source) of a station's gyro: the characterisation uploaded for
    the assignment ("station"), else the simulated gyro's preset ("preset")."""
    station = station_noise(assignment)
    if station is not None:
        return station.noise, station.rate_hz, "station"
    preset = PRESETS.get(preset_name, PRESETS["teaching-fog"])
    return GyroNoise.from_preset(preset), preset.sample_rate_hz, "preset"


def session_plan(db: Session, session: LabSession, dwell_s: float = FIRST_DWELL_S) -> SessionPlan:
    """The plan of ``session``'s station, quoting ``dwell_s`` per position."""
    assignment = db.get(Assignment, session.assignment_id) if session.assignment_id else None
    noise, rate, source = gyro_model(assignment, session.simulator_preset)
    plan = _plan(noise, rate, session.latitude_deg, session.earth_rate_deg_h)
    return SessionPlan(plan, source, session.simulator_preset, dwell_s)


def assignment_plan(assignment: Assignment, dwell_s: float = FIRST_DWELL_S) -> SessionPlan:
    """The plan of an assignment's station (its latitude, Earth rate and gyro)."""
    noise, rate, source = gyro_model(assignment, assignment.simulator_preset)
    plan = _plan(noise, rate, assignment.latitude_deg, assignment.earth_rate_deg_h)
    return SessionPlan(plan, source, assignment.simulator_preset, dwell_s)


@lru_cache(maxsize=256)
def _plan(noise: GyroNoise, rate_hz: float, latitude_deg: float, rate_deg_h: float) -> AccuracyPlan:
    """Plans depend only on the gyro and the station: a class shares one (≈ 20 ms each)."""
    return accuracy_plan(noise, rate_hz, latitude_deg, rate_deg_h)


def two_figures(value: float) -> str:
    """A σ to two significant figures, never in exponent form (0.0031, 0.42, 1.5, 12)."""
    if not math.isfinite(value) or value <= 0:
        return "—"
    decimals = max(0, 1 - math.floor(math.log10(value)))
    return f"{value:.{decimals}f}"


def minutes(seconds: float) -> str:
    return f"{seconds / 60:.1f}" if seconds < 600 else f"{seconds / 60:.0f}"


def plan_view(plan: SessionPlan) -> dict:
    """The planner as the page shows it: one row per dwell (both orders side by side, the
    best of each marked), the sentence for the quoted dwell and each order's best."""
    four = {p.dwell_s: p for p in plan.plan.points if p.order == "1234"}
    eight = {p.dwell_s: p for p in plan.plan.points if p.order == "12344321"}
    best = plan.plan.best
    rows = [
        {
            "dwell": f"{dwell:g}",
            "heading": two_figures(four[dwell].heading_sigma_deg),
            "latitude": two_figures(four[dwell].latitude_sigma_deg),
            "rate": two_figures(four[dwell].earth_rate_sigma_deg_h),
            "time": minutes(four[dwell].total_s),
            "eight_heading": two_figures(eight[dwell].heading_sigma_deg),
            "eight_time": minutes(eight[dwell].total_s),
            "best_four": dwell == best["1234"].dwell_s,
            "best_eight": dwell == best["12344321"].dwell_s,
        }
        for dwell in sorted(four)
    ]
    quoted = plan.plan.at("1234", plan.dwell_s)
    return {
        "rows": rows,
        "source": plan.source,
        "preset": plan.preset_name,
        "quoted": {
            "dwell": f"{quoted.dwell_s:g}",
            "heading": two_figures(quoted.heading_sigma_deg),
            "latitude": two_figures(quoted.latitude_sigma_deg),
            "rate": two_figures(quoted.earth_rate_sigma_deg_h),
        },
        "best": {
            order: {
                "dwell": f"{point.dwell_s:g}",
                "heading": two_figures(point.heading_sigma_deg),
                "minutes": minutes(point.total_s),
                "near": f"{plan.plan.near_best[order].dwell_s:g}",
                "near_minutes": minutes(plan.plan.near_best[order].total_s),
            }
            for order, point in best.items()
        },
    }
