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
UNIT_SYMBOLS = {DEG_PER_HOUR: "°/h", DEG_PER_SECOND: "°/s", RAD_PER_SECOND: "rad/s"}  # as shown
ALIASES = {
    "°/h": DEG_PER_HOUR,
    "deg/hr": DEG_PER_HOUR,
    "dph": DEG_PER_HOUR,
    "°/s": DEG_PER_SECOND,
    "dps": DEG_PER_SECOND,
    "rad/sec": RAD_PER_SECOND,
}

SECONDS_PER_HOUR = 3600.0
MAX_RATE_DEG_H = 1e12  # far beyond any gyro; past it sums and squares would overflow
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


UNIT_SLIP_TOLERANCE = 1.5  # a ratio within 1.5× of a unit's factor names that unit


def unit_slip(measured_deg_h: float, expected_deg_h: float, chosen: str) -> str | None:
    """The unit readings were likely recorded in, when they were saved as ``chosen``.

    Readings recorded in unit u but saved as unit c come out scaled by
    k = F(c) / F(u), F the factor to °/h (1 °/s = 3600 °/h, 1 rad/s = 206 264.8 °/h): °/s
    saved as °/h are 3600× small, rad/s saved as °/s 57.3× small, °/s saved as rad/s 57.3×
    large.  The amplitude a four-position fit measures is a multiple of Earth's rate known
    beforehand (Ω·cos φ in the horizontal plane, Ω in the meridian plane), so a measured /
    expected ratio within ``UNIT_SLIP_TOLERANCE`` of one such k names u; noise and a wrong
    latitude move it by far less than the smallest k (57.3).

    Parameters
    ----------
    measured_deg_h : float
        The amplitude (or Earth rate) measured, °/h as saved.
    expected_deg_h : float
        What Earth's rotation gives there, °/h.
    chosen : str
        The unit the readings were saved as.

    Returns
    -------
    str or None
        The likely unit, or None when the ratio matches none (or cannot be formed).
    """
    if not (measured_deg_h > 0 and expected_deg_h > 0):  # NaN fails too
        return None
    ratio = measured_deg_h / expected_deg_h
    if not math.isfinite(ratio):
        return None
    chosen = canonical_unit(chosen)
    for unit, factor in TO_DEG_PER_HOUR.items():
        if unit == chosen:
            continue
        k = TO_DEG_PER_HOUR[chosen] / factor
        if abs(math.log(ratio / k)) < math.log(UNIT_SLIP_TOLERANCE):
            return unit
    return None


PLAUSIBLE_FLOOR_DEG_H = (1e-4, 1e3)  # the Allan floor of any gyro at rest, °/h


def unit_doubt(adev_min_deg_h: float) -> dict | None:
    """A note when the Allan floor (the curve's minimum) is no gyro's at rest in °/h.

    Gyros' floors run from ≈ 1e-3 °/h (navigation and strategic FOGs, RLGs) to ≈ 10² °/h
    (consumer MEMS); outside [1e-4, 1e3] °/h the readings were most likely in another
    unit than the one they were read in -- a FOG's 0.05 °/h floor read from rad/s as °/h
    is 2.4e-7 -- or the gyro was not at rest.

    Parameters
    ----------
    adev_min_deg_h : float
        The Allan deviation's minimum (°/h), as read.

    Returns
    -------
    dict or None
        The note ``allan.note_unit_doubt`` (key and parameters), or None.
    """
    low, high = PLAUSIBLE_FLOOR_DEG_H
    if low <= adev_min_deg_h <= high or not math.isfinite(adev_min_deg_h):
        return None
    return {"key": "allan.note_unit_doubt", "params": {"floor": f"{adev_min_deg_h:.3g}"}}


def check_named_unit(named: str | None, chosen: str | None) -> None:
    """Refuse readings said to be in one rate unit when their file names another.

    Parameters
    ----------
    named : str or None
        The canonical unit the file's header or row of units names ("deg/s"), if any.
    chosen : str or None
        The canonical unit the readings are said to be in, if any.

    Returns
    -------
    None
        Where the two agree, or either is not given.

    Raises
    ------
    UserError
        ``csv.unit_conflict`` with both units' symbols, where both are given and differ
        (°/s read as °/h would be 3600 times too small).
    """
    if named is not None and chosen is not None and named != chosen:
        raise UserError(
            "csv.unit_conflict", header=UNIT_SYMBOLS[named], chosen=UNIT_SYMBOLS[chosen]
        )
