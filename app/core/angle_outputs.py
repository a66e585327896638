"""A static record of angles turned into rates: gyros that output each period's angle
increment Δθ (KVH's "delta angle", the Δθ of Honeywell's and Northrop Grumman's IMUs) or
the integrated angle θ (a DSP-3000's "integrated angle") instead of a rate.

* increments: ω_k = Δθ_k · f, f the output rate -- the increment is the rate integrated
  over the output's own period (KVH DSP-1750 manual, delta-angle output);
* an integrated angle: ω_k = (θ_k − θ_{k−1}) / (t_k − t_{k−1}), or · f without times --
  one rate fewer than angles.

The header names the unit (an angle: rad, mrad, µrad, deg, arcsec) and, where the name
says so ("delta", "dtheta", "increment"; "integrated"), the kind; otherwise the readings
tell it (:func:`angle_kind`).  The units a header names: :mod:`app.core.column_names`.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from app.core.column_names import AngleOutput
from app.core.exceptions import UserError
from app.core.record_checks import sample_rate_hz
from app.core.static_record import StaticRecord
from app.core.units import SECONDS_PER_HOUR

INTEGRATED_RATIO = 0.3  # std(Δx) / std(x) below it: an integrated angle


def angle_kind(angles: np.ndarray) -> str:
    """Increments or an integrated angle, told from the readings by ρ = std(Δx) / std(x).

    A gyro at rest gives increments that are white noise about a constant (angle random
    walk and the angle's rounding, per output): consecutive ones are independent, so
    ρ ≈ √2.  Its integrated angle is a random walk (those increments summed) plus a ramp
    (Earth's rate and the bias), whose spread grows with the record: ρ ≈ √(6/n) for a
    random walk of n outputs (0.08 for 1,000), less with the ramp -- below
    ``INTEGRATED_RATIO`` from about 70 outputs on.

    Parameters
    ----------
    angles : numpy.ndarray
        The readings (any angle unit).

    Returns
    -------
    str
        "integrated" or "increment".
    """
    spread = float(np.std(angles))
    if angles.size < 3 or not spread > 0:
        return "increment"
    steps = float(np.std(np.diff(angles)))
    return "integrated" if steps < INTEGRATED_RATIO * spread else "increment"


def _output_rate(record: StaticRecord, rate_hz: float | None) -> float:
    if rate_hz is not None:
        return rate_hz
    if record.times_s is None or record.times_s.size < 2:
        raise UserError("allan.no_rate")
    rate = sample_rate_hz(record.times_s)  # the mean: increments × a median's rate are off
    if not rate > 0:
        raise UserError("allan.bad_times")
    return rate


def rates_from_angles(
    record: StaticRecord, angle: AngleOutput, rate_hz: float | None
) -> tuple[StaticRecord, list[dict]]:
    """The record's angles as rates in °/h, and notes saying how.

    Parameters
    ----------
    record : StaticRecord
        Angles in ``angle.unit`` per output, with their times where the record has them.
    angle : AngleOutput
        The header's angle unit and, where it says, the kind.
    rate_hz : float or None
        The output rate f (Hz); None: from the times' median step.

    Returns
    -------
    (StaticRecord, list of dict)
        The rates (°/h), their times and temperatures (an integrated angle: from the
        second output on); the notes (``allan.note_angle_increment`` or
        ``allan.note_angle_integrated``, and ``allan.note_angle_told`` where the readings
        told the kind).

    Raises
    ------
    UserError
        ``allan.no_rate`` without a rate or times; ``allan.bad_times``.
    """
    degrees = np.asarray(record.values, dtype=float) * angle.deg_per_unit
    kind = angle.kind or angle_kind(degrees)
    rate = _output_rate(record, rate_hz)
    times, temperatures = record.times_s, record.temperatures_c
    if kind == "increment":
        rates = degrees * rate * SECONDS_PER_HOUR
    else:
        steps = np.diff(degrees)
        if times is not None:
            seconds = np.diff(times)
            if not np.all(seconds > 0):
                raise UserError("allan.bad_times")
            rates = steps / seconds * SECONDS_PER_HOUR
            times = times[1:]
        else:
            rates = steps * rate * SECONDS_PER_HOUR
        temperatures = None if temperatures is None else temperatures[1:]
    said = {"unit": angle.unit, "rate": f"{rate:g}"}
    notes = [{"key": f"allan.note_angle_{kind}", "params": said}]
    if angle.kind is None:
        notes.append({"key": "allan.note_angle_told", "params": {}})
    return replace(record, values=rates, times_s=times, temperatures_c=temperatures), notes
