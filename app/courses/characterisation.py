"""A real gyro's Allan characterisation, uploaded by the teacher for an assignment.

The teacher records the bench's gyro at rest (ideally hours, after warm-up) and uploads
the record with its sample rate.  Its IEEE 952 terms (joint fit, with bootstrap 68 %
intervals) are stored on the assignment; from then on the position means of readings that
did not come from the simulated gyro (typed, CSV, API, the serial bridge) get their
covariance from that noise model -- ``uncertainty_model`` "allan" -- instead of assuming
white noise (lab-reference §3).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from datetime import UTC, datetime

import numpy as np

from app.core.allan import allan_deviation
from app.core.allan_intervals import fit_intervals
from app.core.exceptions import UserError
from app.core.noise_model import GyroNoise
from app.core.position_records import parse_static_record
from app.core.units import canonical_unit, to_deg_per_hour
from app.models import Assignment, utcnow

MAX_RATE_HZ = 10_000.0
MIN_RECORD_S = 600.0  # shorter records say little about the slow terms
REPLICATES = 20


@dataclass(frozen=True)
class StationNoise:
    """The characterised gyro: its noise model and the rate its readings come at."""

    noise: GyroNoise
    rate_hz: float


def characterise(text: str, rate_hz: float, unit: str = "deg/h") -> dict:
    """Fit the record's Allan deviation; the stored summary (JSON-ready)."""
    if not (isinstance(rate_hz, int | float) and math.isfinite(rate_hz)) or not (
        0 < rate_hz <= MAX_RATE_HZ
    ):
        raise UserError(
            "characterisation.bad_rate",
            "The sample rate must be a number of readings per second, up to 10000.",
        )
    values = to_deg_per_hour(parse_static_record(text), canonical_unit(unit))
    seconds = values.size / rate_hz
    if seconds < MIN_RECORD_S:
        raise UserError(
            "characterisation.too_short",
            f"The record covers {seconds:.0f} s; at least {MIN_RECORD_S:.0f} s (better: hours) "
            "are needed to see the slow terms.",
            seconds=round(seconds),
            minimum=round(MIN_RECORD_S),
        )
    result = allan_deviation(values, rate_hz)
    intervals = fit_intervals(result, rate_hz, values.size, replicates=REPLICATES)
    return {
        "rate_hz": float(rate_hz),
        "samples": int(values.size),
        "record_s": float(seconds),
        "arw_deg_rt_h": result.arw_deg_rt_h,
        "arw_interval": list(intervals.arw_deg_rt_h),
        "bias_instability_deg_h": result.bias_instability_deg_h or 0.0,
        "bias_instability_interval": list(intervals.bias_instability_deg_h or (0.0, 0.0)),
        "bias_corr_time_s": result.bias_corr_time_s or 0.0,
        "rrw_deg_h_rt_h": result.rrw_deg_h_rt_h or 0.0,
        "quantization_deg": result.quantization_deg,
        "recommended_dwell_s": result.recommended_dwell_s,
        "uploaded_at": utcnow().strftime("%Y-%m-%d %H:%M"),
    }


def store(assignment: Assignment, summary: dict | None) -> None:
    assignment.gyro_characterisation = None if summary is None else json.dumps(summary)


def summary_of(assignment: Assignment | None, with_time: bool = False) -> dict | None:
    """The stored characterisation; ``with_time`` adds ``uploaded``, the upload's aware UTC
    datetime (stored as "YYYY-MM-DD HH:MM" UTC) for pages that show it in local time."""
    if assignment is None or not assignment.gyro_characterisation:
        return None
    summary = json.loads(assignment.gyro_characterisation)
    if with_time:
        try:
            uploaded = datetime.strptime(summary.get("uploaded_at", ""), "%Y-%m-%d %H:%M")
            summary["uploaded"] = uploaded.replace(tzinfo=UTC)
        except ValueError:
            summary["uploaded"] = None
    return summary


def station_noise(assignment: Assignment | None) -> StationNoise | None:
    """The assignment's characterised gyro, if the teacher uploaded one."""
    summary = summary_of(assignment)
    if summary is None:
        return None
    noise = GyroNoise(
        arw_deg_rt_h=summary["arw_deg_rt_h"],
        bias_instability_deg_h=summary["bias_instability_deg_h"],
        bias_corr_time_s=summary["bias_corr_time_s"],
        rrw_deg_h_rt_h=summary["rrw_deg_h_rt_h"],
        angle_lsb_deg=summary["quantization_deg"] * float(np.sqrt(12.0)),
    )
    return StationNoise(noise, summary["rate_hz"])
