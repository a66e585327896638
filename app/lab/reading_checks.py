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
    position: int,
    angle_deg: float,
    times: np.ndarray | None,
    n_values: int,
    first_reading: int = 1,
) -> None:
    """A finite dial angle within ten turns; sample times, if any, one per value, finite,
    each later than the one before (the drift fit and the warm-up check read them as one
    clock: a clock set back, or two recordings run together, would give a wrong drift);
    ``first_reading``: the number of the first value among the position's readings (an
    append's first is after those stored), for the message."""
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
    if times is not None and times.size > 1:
        steps = np.diff(times)
        if not np.all(steps > 0):
            at = int(np.argmax(steps <= 0)) + 1  # the first reading not after the one before
            raise UserError(
                "lab.times_not_rising",
                position=position,
                reading=first_reading + at,
                time=_seconds(times[at]),
                before=_seconds(times[at - 1]),
            )


def check_times_follow(position: int, last_stored_s: float | None, times: np.ndarray) -> None:
    """An appended batch's first time after the last one stored (one clock, rising)."""
    if last_stored_s is not None and times.size and not times[0] > last_stored_s:
        raise UserError(
            "lab.times_not_after",
            position=position,
            time=_seconds(times[0]),
            last=_seconds(last_stored_s),
        )


def _seconds(value: float) -> str:
    """A time as a person reads it in a message: up to six decimals, none trailing."""
    return f"{float(value):.6f}".rstrip("0").rstrip(".")


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
