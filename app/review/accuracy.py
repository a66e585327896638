"""The class's accuracy against the plan: each submitted group's errors over the 1σ the
planner predicts for its dwell and order (``app.core.accuracy_plan.scatter_agreement``)."""

from __future__ import annotations

import statistics
from functools import lru_cache

import numpy as np

from app.core.accuracy_plan import ORDERS, plan_point, scatter_agreement
from app.lab.planner import gyro_model, two_figures
from app.models import Assignment

QUANTITIES = ("heading", "latitude", "earth_rate")
# a class shares a few dwells and one station: each plan point is worked out once
planned = lru_cache(maxsize=4096)(plan_point)
_ORDER_OF = {len(stops): order for order, stops in ORDERS.items()}  # 4 → 1234, 8 → 1234…


def group_errors(row) -> dict[str, tuple[float, int, int]]:
    """One submitted group's errors against its truth: quantity → (error, median readings
    per position, positions) from its latest attempt (what the teacher grades)."""
    found = {}
    heading, latitude = row.results.get("heading"), row.results.get("latitude")
    error = row.check_error("heading")
    if heading and error is not None:
        found["heading"] = (
            error,
            int(statistics.median(heading["samples_per_position"])),
            heading["n_positions"],
        )
    if latitude and row.session is not None:
        counts = int(statistics.median(latitude["samples_per_position"]))
        if latitude.get("latitude_error_deg") is not None:
            found["latitude"] = (latitude["latitude_error_deg"], counts, latitude["n_positions"])
        rate_error = latitude["earth_rate_deg_h"] - row.session.earth_rate_deg_h
        found["earth_rate"] = (rate_error, counts, latitude["n_positions"])
    return found


def _dwell(row, quantity: str, count: int, rate_hz: float) -> float:
    """The time a group's positions averaged over: what its readings' times say where it
    recorded them itself (a device faster than the characterisation's record averages
    over less than its count at that rate, as the result's σ takes it), else the count at
    the gyro's rate."""
    part = "heading" if quantity == "heading" else "latitude"
    evidence = getattr(row, "data_evidence", None)
    seconds = evidence.seconds.get(part) if evidence is not None else None
    return seconds if seconds else count / rate_hz


def class_accuracy(assignment: Assignment, rows) -> dict:
    """Per quantity: the groups compared, their median dwell, the predicted 1σ there, the
    measured RMS error, R = RMS(e/σ) with its 95 % range, and the verdict."""
    noise, rate_hz, _source = gyro_model(assignment, assignment.simulator_preset)
    errors = {name: [] for name in QUANTITIES}
    for row in rows:
        if row.latest is None or row.session is None:
            continue
        session = row.session
        for name, (error, count, positions) in group_errors(row).items():
            order = _ORDER_OF.get(positions)
            if order is None or count < 1:
                continue  # a plan exists for four positions and the symmetric eight
            dwell = _dwell(row, name, count, rate_hz)
            point = planned(
                noise, rate_hz, dwell, order, session.latitude_deg, session.earth_rate_deg_h
            )
            sigma = {
                "heading": point.heading_sigma_deg,
                "latitude": point.latitude_sigma_deg,
                "earth_rate": point.earth_rate_sigma_deg_h,
            }[name]
            errors[name].append((float(error), sigma, dwell))
    summary = {}
    for name, items in errors.items():
        if not items:
            continue
        error, sigma, dwell = (np.array(column) for column in zip(*items, strict=True))
        agreement = scatter_agreement(error, sigma)
        summary[name] = {
            **agreement.to_json(),
            "median_dwell_s": float(np.median(dwell)),
            "predicted_sigma": float(np.median(sigma)),
            "measured_rms": float(np.sqrt(np.mean(error * error))),
        }
    return summary


def accuracy_rows(summary: dict) -> list[dict]:
    """The summary as the dashboard's table shows it (two significant figures)."""
    return [
        {
            "quantity": name,
            "groups": item["groups"],
            "dwell": f"{item['median_dwell_s']:.0f}",
            "predicted": two_figures(item["predicted_sigma"]),
            "measured": two_figures(item["measured_rms"]),
            "ratio": f"{item['ratio']:.2f}",
            "range": f"{item['low']:.2f}–{item['high']:.2f}",
            "verdict": item["verdict"],
        }
        for name, item in summary.items()
    ]
