"""What a position's readings must be before they are stored, whatever brought them (a
grid, a file, the API, the stream): finite rates a gyro at rest can read, a dial angle
and sample times that make sense, case temperatures a sensor can report."""

from __future__ import annotations

import math

import numpy as np

from app.core.exceptions import UserError
from app.core.sinusoid import MAX_ANGLE_DEG
from app.models import LabSession

PLAUSIBLE_RATE_DEG_H = 7200.0  # 2 °/s: a gyro at rest reads Earth's rate plus its bias
PLAUSIBLE_TEMPERATURE_C = 200.0  # a case temperature beyond ±200 °C is a decoding error


def check_angle_and_times(
    position: int, angle_deg: float, times: np.ndarray | None, n_values: int
) -> None:
    """A finite dial angle within ten turns; sample times, if any, one per value, finite."""
    if not math.isfinite(angle_deg) or abs(angle_deg) > MAX_ANGLE_DEG:
        raise UserError(
            "lab.bad_angle",
            position=position,
            limit=MAX_ANGLE_DEG,
        )
    if times is not None and (times.size != n_values or not np.all(np.isfinite(times))):
        raise UserError(
            "lab.bad_times",
            position=position,
        )


def check_temperatures(position: int, temperatures: np.ndarray | None, n_values: int) -> None:
    """Case temperatures, if any: one per value, finite, within ±200 °C."""
    if temperatures is None:
        return
    if (
        temperatures.size != n_values
        or not np.all(np.isfinite(temperatures))
        or float(np.max(np.abs(temperatures), initial=0.0)) > PLAUSIBLE_TEMPERATURE_C
    ):
        raise UserError(
            "lab.bad_temperatures",
            position=position,
            limit=PLAUSIBLE_TEMPERATURE_C,
        )


def check_values(session: LabSession, position: int, values: np.ndarray) -> None:
    """Finite rates no larger than a gyro at rest can read (2 °/s)."""
    if not np.all(np.isfinite(values)):
        raise UserError("readings.not_finite", position=position)
    if values.size and max(float(values.max()), -float(values.min())) > PLAUSIBLE_RATE_DEG_H:
        raise UserError(
            "lab.implausible_rate",
            position=position,
        )
