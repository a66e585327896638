"""The data-quality flags of a part's result: too few readings, spikes, gaps in a timed
record, a gyro still warming up (its temperature, or the bias drifting over the run), a
position far noisier than the rest, and readings that look recorded in another unit.

Each flag is ``{"key": message key, "params": {...}}``: the words are the catalogues'.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from app.core.drift_check import warm_up_message
from app.core.record_checks import count_spikes, record_gaps, warm_up_change
from app.core.units import TO_DEG_PER_HOUR, UNIT_SYMBOLS, unit_slip
from app.lab.sim import preset_for
from app.models import LabSession

if TYPE_CHECKING:
    from app.lab.results import PositionData


@dataclass(frozen=True, slots=True)
class PositionChecks:
    """What the data-quality flags need of one position's used readings, made once per
    take (a class's dashboard keeps them: :mod:`app.review.take_summaries`)."""

    n: int
    std: float | None
    spikes: int
    gaps: int = 0  # lost-reading gaps in a timed record (0 untimed)
    missing: int = 0
    warm_up: float | None = None  # the reported temperature's change (°C), when it moved


def position_checks(item: PositionData) -> PositionChecks:
    """:class:`PositionChecks` of a position's readings (with their samples)."""
    n = int(item.values.size)
    gaps, missing = record_gaps(item.times) if item.times is not None else (0, 0)
    return PositionChecks(
        n,
        item.std if n >= 2 else None,
        count_spikes(item.values) if n >= 2 else 0,
        gaps,
        missing,
        warm_up_change(item.temperatures) if item.temperatures is not None else None,
    )


def quality_flags(session: LabSession, data: dict[int, PositionData]) -> list[dict]:
    """Data-quality warnings: too few readings, spikes, gaps in a timed record (readings
    lost between the gyro and the server), a gyro still warming up (its reported
    temperature moved over 1 °C), a position far noisier than the rest.

    Each flag is ``{"key": message key, "params": {...}}``.
    """
    return flags_of_checks(session, {k: position_checks(item) for k, item in data.items()})


def flags_of_checks(session: LabSession, checks: dict[int, PositionChecks]) -> list[dict]:
    """:func:`quality_flags` from each position's :class:`PositionChecks`."""

    def flag(key: str, **params) -> dict:
        return {"key": key, "params": params}

    flags = []
    stds = {}
    for position, item in sorted(checks.items()):
        if item.n < session.min_readings:
            flags.append(
                flag("flag.too_few", position=position, n=item.n, minimum=session.min_readings)
            )
        if item.n >= 2:
            stds[position] = item.std
            if item.spikes:
                flags.append(flag("flag.spikes", position=position, n=item.spikes))
        if item.gaps:
            flags.append(flag("flag.gaps", position=position, n=item.gaps, missing=item.missing))
        if item.warm_up is not None:
            flags.append(flag("flag.warm_up", position=position, change=f"{item.warm_up:.1f}"))
    if len(stds) >= 3:
        typical = float(np.median(list(stds.values())))
        for position, std in stds.items():
            if typical > 0 and std > 3 * typical:
                flags.append(flag("flag.noisy", position=position, ratio=round(std / typical, 1)))
    return flags


def unit_slip_flag(session: LabSession, part: str, ordered: list[PositionData], result):
    """A flag when the part's readings look recorded in another unit than the one they
    were saved as (°/s saved as °/h: Ω 3600× small), by :func:`app.core.units.unit_slip`
    on the fit's amplitude (heading: against Ω·cos φ) or Earth rate (latitude: Ω).  Only
    the unit is named, never the expected value (a secret truth stays secret)."""
    units = {p.take.unit for p in ordered}
    if result is None or len(units) != 1:
        return None
    chosen = units.pop()
    if part == "heading":
        horizontal = math.cos(math.radians(session.latitude_deg))
        if horizontal < 0.1:  # within 6° of a pole the horizontal amplitude is no guide
            return None
        measured, expected = result.amplitude_deg_h, session.earth_rate_deg_h * horizontal
    else:
        measured, expected = result.earth_rate_deg_h, session.earth_rate_deg_h
    likely = unit_slip(measured, expected, chosen)
    if likely is None:
        return None
    factor = TO_DEG_PER_HOUR[chosen] / TO_DEG_PER_HOUR[likely]
    return {
        "key": "flag.unit_slip",
        "params": {
            "factor": f"{max(factor, 1 / factor):.0f}",
            "likely": UNIT_SYMBOLS[likely],
            "chosen": UNIT_SYMBOLS.get(chosen, chosen),
        },
    }


def warm_up_flag(session: LabSession, check, simulated_until_s: float | None) -> dict:
    """The words for a run whose bias drifted (a gyro still warming up) -- for the simulated
    gyro (``simulated_until_s``: the gyro time its run ended), how long it still needed
    then until five warm-up time constants after switch-on."""
    minutes = None
    preset = preset_for(session)
    if simulated_until_s is not None and preset.warmup_time_constant_s > 0:
        left = 5.0 * preset.warmup_time_constant_s - simulated_until_s
        minutes = max(1, math.ceil(left / 60.0)) if left > 0 else 0
    key, params = warm_up_message(check, minutes)
    return {"key": key, "params": params}
