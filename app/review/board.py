"""The class board: the Earth measured together.  Every group's heading error, latitude and
Earth rate with its 1σ as they arrive (a group's submitted attempt, else its current data),
the class's pooled latitude and Earth rate with their standard errors beside the true
values, and the horizontal component against cos φ where several stations contribute.

Pooling is the inverse-variance weighted mean, x̄ = Σw_i·x_i/Σw_i with w_i = 1/σ_i², its
standard error 1/√Σw_i widened by the Birge ratio √(χ²/(k − 1)) when the groups scatter
more than their σ say (χ² = Σw_i·(x_i − x̄)²) -- the particle data group's practice.
Groups are numbered, never named, unless the teacher chooses to show names."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from sqlmodel import Session

from app.core.sinusoid import wrap180
from app.lab.result_cache import cached_results
from app.models import Assignment

VALUES = (
    "amplitude_deg_h",
    "amplitude_sigma_deg_h",
    "heading_error_deg",
    "heading_sigma_deg",
    "latitude_deg",
    "latitude_sigma_deg",
    "earth_rate_deg_h",
    "earth_rate_sigma_deg_h",
)
OUTLIER_Z = 3.0  # a group this many of its own σ from the pooled value is marked


@dataclass(frozen=True)
class Pooled:
    value: float
    standard_error: float
    groups: int
    birge: float  # √(χ²/(k − 1)); 1 when the scatter is what the σ say

    def to_json(self) -> dict:
        return {
            "value": self.value,
            "standard_error": self.standard_error,
            "groups": self.groups,
            "birge_ratio": self.birge,
        }


def pooled(values: list[float], sigmas: list[float]) -> Pooled | None:
    """The inverse-variance weighted mean of the groups' values (module docstring)."""
    pairs = [
        (v, s)
        for v, s in zip(values, sigmas, strict=True)
        if v is not None and s is not None and math.isfinite(v) and s > 0
    ]
    if not pairs:
        return None
    x = np.array([v for v, _ in pairs])
    w = 1.0 / np.array([s for _, s in pairs]) ** 2
    mean = float(np.sum(w * x) / np.sum(w))
    error = 1.0 / math.sqrt(float(np.sum(w)))
    birge = 1.0
    if len(pairs) > 1:
        chi2 = float(np.sum(w * (x - mean) ** 2))
        birge = max(1.0, math.sqrt(chi2 / (len(pairs) - 1)))
    return Pooled(mean, error * birge, len(pairs), birge)


def group_results(db: Session, assignment: Assignment, row) -> dict:
    """A group's results as the board shows them: its submitted attempt, else its data now."""
    if row.results:
        return row.results
    entry = cached_results(db, row.session, assignment)
    return {
        part: outcome.result.to_json() if outcome.result is not None else None
        for part, outcome in entry.parts.items()
    }


def board_data(db: Session, assignment: Assignment, rows, names: bool = False) -> dict:
    """Every group's point and the pooled values, ready for the page and the API."""
    seen_sessions: set[int] = set()
    groups = []
    for row in rows:
        if row.session is None or row.session.id in seen_sessions:
            continue  # lab partners share one session: one point
        seen_sessions.add(row.session.id)
        results = group_results(db, assignment, row)
        heading, latitude = results.get("heading"), results.get("latitude")
        if not heading and not latitude:
            continue
        truth = row.truth
        point = {
            "label": "+".join(row.group) if row.group else row.student.username,
            "submitted": bool(row.results),
            "true_latitude_deg": row.session.latitude_deg,
            "true_earth_rate_deg_h": row.session.earth_rate_deg_h,
            **dict.fromkeys(VALUES),  # every quantity present, None until measured
        }
        if heading:
            point["amplitude_deg_h"] = heading.get("amplitude_deg_h")
            point["amplitude_sigma_deg_h"] = heading.get("amplitude_sigma_deg_h")
            if truth is not None and truth.azimuth_deg is not None:
                point["heading_error_deg"] = wrap180(heading["azimuth_deg"] - truth.azimuth_deg)
                point["heading_sigma_deg"] = heading.get("azimuth_sigma_deg")
        if latitude:
            point["latitude_deg"] = latitude.get("latitude_deg")
            point["latitude_sigma_deg"] = latitude.get("latitude_sigma_deg")
            point["earth_rate_deg_h"] = latitude.get("earth_rate_deg_h")
            point["earth_rate_sigma_deg_h"] = latitude.get("earth_rate_sigma_deg_h")
        groups.append(point)
    groups.sort(key=lambda p: p["label"])
    for number, point in enumerate(groups, 1):
        point["number"] = number
        if not names:
            point["label"] = None

    def column(name):
        return [p.get(name) for p in groups]

    rate = pooled(column("earth_rate_deg_h"), column("earth_rate_sigma_deg_h"))
    latitude = pooled(column("latitude_deg"), column("latitude_sigma_deg"))
    for point in groups:
        point["outlier"] = any(
            _far(point.get(value), point.get(sigma), pool)
            for value, sigma, pool in (
                ("earth_rate_deg_h", "earth_rate_sigma_deg_h", rate),
                ("latitude_deg", "latitude_sigma_deg", latitude),
            )
        )
    stations = {round(p["true_latitude_deg"], 3) for p in groups}
    return {
        "groups": groups,
        "earth_rate": rate.to_json() if rate else None,
        "latitude": latitude.to_json() if latitude else None,
        "true_earth_rate_deg_h": assignment.earth_rate_deg_h,
        "true_latitude_deg": assignment.latitude_deg,
        "several_stations": len(stations) > 1,
        "names_shown": names,
    }


def _far(value, sigma, pool: Pooled | None) -> bool:
    if value is None or sigma is None or pool is None or not sigma > 0:
        return False
    return abs(value - pool.value) > OUTLIER_Z * math.hypot(sigma, pool.standard_error)
