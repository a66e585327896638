"""Angular-rate units.  Everything inside GyroLab is °/h; convert only at the boundary.

1 °/s = 3600 °/h;  1 rad/s = (180/π)·3600 °/h ≈ 206 264.8 °/h.
"""

from __future__ import annotations

import math

import numpy as np

from app.core.exceptions import UserError

DEG_PER_HOUR = "deg/h"
DEG_PER_SECOND = "deg/s"
RAD_PER_SECOND = "rad/s"
TO_DEG_PER_HOUR: dict[str, float] = {
    DEG_PER_HOUR: 1.0,
    DEG_PER_SECOND: 3600.0,
    RAD_PER_SECOND: math.degrees(1.0) * 3600.0,
}
UNITS = tuple(TO_DEG_PER_HOUR)
ALIASES = {
    "°/h": DEG_PER_HOUR,
    "deg/hr": DEG_PER_HOUR,
    "dph": DEG_PER_HOUR,
    "°/s": DEG_PER_SECOND,
    "dps": DEG_PER_SECOND,
    "rad/sec": RAD_PER_SECOND,
}

SECONDS_PER_HOUR = 3600.0
EARTH_RATE_DEG_H = 15.041  # sidereal: 360° / 23.9345 h
HANDOUT_EARTH_RATE_DEG_H = 15.04


def canonical_unit(unit: str) -> str:
    """The unit's canonical name: "deg/h", "deg/s" or "rad/s" (aliases such as "°/h" accepted).

    Parameters
    ----------
    unit : str
        A rate unit as typed.

    Returns
    -------
    str
        Its canonical name.

    Raises
    ------
    UserError
        ``unit.unknown`` for anything else.
    """
    name = ALIASES.get(unit.strip(), unit.strip())
    if name not in TO_DEG_PER_HOUR:
        raise UserError("unit.unknown", unit=unit)
    return name


def to_deg_per_hour(values, unit: str = DEG_PER_HOUR) -> np.ndarray:
    """Rates in °/h (1 °/s = 3600 °/h; 1 rad/s = 3600·180/π °/h).

    Parameters
    ----------
    values : array_like
        Rates in ``unit``.
    unit : str
        Their unit.

    Returns
    -------
    numpy.ndarray
        The rates in °/h.

    Raises
    ------
    UserError
        ``readings.out_of_range`` when a finite reading overflows on conversion (1e306 °/s).
    """
    array = np.asarray(values, dtype=float)
    factor = TO_DEG_PER_HOUR[canonical_unit(unit)]
    if factor == 1.0:
        return array  # already °/h: no copy of a large upload
    with np.errstate(over="ignore"):
        converted = array * factor
    if not np.all(np.isfinite(converted)) and np.all(np.isfinite(array)):
        raise UserError(
            "readings.out_of_range",
        )
    return converted


def from_deg_per_hour(values, unit: str = DEG_PER_HOUR) -> np.ndarray:
    """Rates in °/h converted to ``unit`` (the inverse of :func:`to_deg_per_hour`).

    Parameters
    ----------
    values : array_like
        Rates in °/h.
    unit : str
        The unit wanted.

    Returns
    -------
    numpy.ndarray
        The rates in ``unit``.
    """
    return np.asarray(values, dtype=float) / TO_DEG_PER_HOUR[canonical_unit(unit)]
