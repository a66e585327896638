"""A real static record made ready for an Allan analysis: its gaps, spikes and warm-up
found and dealt with, and every step said (lab-reference §6: IEEE practice trims the
warm-up and records the temperature).

Preparation, in this order:

* gaps (the bridge's times skip readings, k·T steps with k ≥ 2 for the median step T):
  the longest stretch without a gap is analysed -- joining across a gap would fake a
  correlation;
* lost readings (NaN or infinity, a logger's mark of a reading it lost): up to
  ``MAX_MENDED_RUN`` in a row are mended by the line between their neighbours and
  counted; a longer run is a gap like the times' (the longest stretch without one is
  analysed);
* disturbances (:func:`disturbances`: the gyro knocked, its output saturated -- readings
  far from the record's level for longer than a spike): the longest stretch without one
  is analysed;
* spikes: readings more than ``SPIKE_LIMIT`` robust σ (1.4826·MAD of the residual from a
  9-point running median, at least one reading step) from their running median are
  replaced by it and counted;
* warm-up: from the case temperature where there is one (the stretch before it settles to
  within 10 % of its total change of its final value), else from the rate itself (64 block
  means; the first more than ``WARM_UP_LIMIT`` times the block-to-block scatter from the
  settled level of the second half, and the first four -- or all until one is back within
  twice the scatter, if fewer -- stepping monotonically towards it): trimmed, at most
  half the record.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from app.core.exceptions import UserError
from app.core.record_checks import sample_rate_hz
from app.core.record_repairs import (
    SPIKE_LIMIT,
    disturbances,
    longest_between,
    mend_lost_readings,
    reading_step,
)
from app.core.static_record import StaticRecord

WARM_UP_LIMIT = 6.0
WARM_UP_BLOCKS = 64
WARM_UP_HEAD = 4  # blocks a warm-up must fall steadily over (fewer if it settles sooner)
MAX_TRIM_SHARE = 0.5
# a clock coarser than the readings ties at least one step in six (1.2 readings a tick);
# fewer ties are a fine clock's stamps written twice (a logger's first line, say)
COARSE_CLOCK_TIES = 0.05


@dataclass
class PreparedRecord:
    values: np.ndarray
    rate_hz: float
    notes: list[dict] = field(default_factory=list)  # {"key", "params"}: words in catalogues


def _note(key: str, **params) -> dict:
    return {"key": key, "params": params}


def _coarse_clock(times: np.ndarray) -> tuple[slice, float, float, int, int] | None:
    """A clock coarser than the readings (a logger stamping whole seconds at 10 Hz): the
    longest stretch without a missing tick, the rate counted in it, the tick, the gaps
    (missed ticks) and the readings they held at that rate -- or None where the times are
    not such a clock.

    The rate is the readings from the stretch's first whole tick to its last tick's
    start over the ticks between: the first and last ticks are seen only in part.
    """
    steps = np.diff(times)
    if not steps.size or np.any(steps < 0) or np.mean(steps == 0) < COARSE_CLOCK_TIES:
        return None
    ticks = steps[steps > 0]
    if ticks.size < 2:
        return None
    tick = float(np.median(ticks))
    breaks = np.flatnonzero(steps >= 1.5 * tick)
    edges = np.concatenate([[0], breaks + 1, [times.size]])
    longest = int(np.argmax(np.diff(edges)))
    start, stop = int(edges[longest]), int(edges[longest + 1])
    changes = start + 1 + np.flatnonzero(steps[start : stop - 1] > 0)  # each tick's first
    if changes.size < 2:
        return None
    first, last = int(changes[0]), int(changes[-1])
    rate = (last - first) / float(times[last] - times[first])
    missed_s = float(np.sum(np.rint(steps[breaks] / tick) - 1)) * tick
    return slice(start, stop), rate, tick, int(breaks.size), round(missed_s * rate)


def _longest_stretch(times: np.ndarray) -> tuple[slice, int, int, float, int]:
    """The longest stretch without a gap, how many gaps, the readings they missed, the
    median step, and how many stamps tie with the one before.  A few tied stamps (fewer
    than ``COARSE_CLOCK_TIES`` of the steps) are a fine clock's stamp written twice: the
    readings stay in order, one step each."""
    steps = np.diff(times)
    interval = float(np.median(steps)) if steps.size else 0.0
    if not (interval > 0 and math.isfinite(interval)):
        raise UserError("allan.bad_times")
    breaks = np.flatnonzero(steps >= 1.5 * interval)
    tied = int(np.count_nonzero(steps == 0))
    if np.any(steps < 0) or tied >= COARSE_CLOCK_TIES * steps.size:
        raise UserError("allan.bad_times")
    edges = np.concatenate([[0], breaks + 1, [times.size]])
    lengths = np.diff(edges)
    longest = int(np.argmax(lengths))
    missing = int(np.sum(np.rint(steps[breaks] / interval) - 1))
    stretch = slice(int(edges[longest]), int(edges[longest + 1]))
    return stretch, int(breaks.size), missing, interval, tied


def _despike(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    from scipy.ndimage import median_filter

    smooth = median_filter(values, size=9, mode="nearest")
    residual = values - smooth
    scale = 1.4826 * float(np.median(np.abs(residual)))
    scale = max(scale, reading_step(values))
    if scale <= 0:
        return values, np.zeros(0, dtype=int)
    spikes = np.flatnonzero(np.abs(residual) > SPIKE_LIMIT * scale)
    if spikes.size:
        values = values.copy()
        values[spikes] = smooth[spikes]
    return values, spikes


def _warm_up_end(values: np.ndarray, temperatures: np.ndarray | None) -> tuple[int, str, float]:
    """Index where the warm-up ends (0: none), how it was seen, and its size (°/h or °C)."""
    limit = int(values.size * MAX_TRIM_SHARE)
    if temperatures is not None and temperatures.size == values.size:
        final = float(np.median(temperatures[-max(1, temperatures.size // 10) :]))
        change = float(np.max(temperatures) - np.min(temperatures))
        if change > 1.0:
            unsettled = np.flatnonzero(np.abs(temperatures - final) > 0.1 * change)
            end = int(unsettled[-1]) + 1 if unsettled.size else 0
            if end:
                return min(end, limit), "temperature", change
    size = values.size // WARM_UP_BLOCKS
    if size < 4:
        return 0, "", 0.0
    means = values[: size * WARM_UP_BLOCKS].reshape(WARM_UP_BLOCKS, size).mean(axis=1)
    settled = means[WARM_UP_BLOCKS // 2 :]
    level = float(np.median(settled))
    scatter = 1.4826 * float(np.median(np.abs(np.diff(settled)))) / math.sqrt(2.0)
    if scatter <= 0:
        return 0, "", 0.0
    deviation = means - level
    if abs(deviation[0]) < WARM_UP_LIMIT * scatter:
        return 0, "", 0.0
    sign = np.sign(deviation[0])
    inside = np.flatnonzero(np.abs(deviation) < 2.0 * scatter)
    # a warm-up moves steadily towards the settled level: over its first four blocks, or
    # over all of it when it settles sooner (a 5-minute warm-up in an 8-hour record's
    # 450-s blocks is one or two blocks, the next ones the settled scatter)
    away = int(inside[0]) if inside.size else WARM_UP_BLOCKS
    head = deviation[: min(away, WARM_UP_HEAD)] * sign
    if not np.all(np.diff(head) < 0):
        return 0, "", 0.0
    end_block = int(inside[0]) if inside.size else WARM_UP_BLOCKS // 2
    return min(end_block * size, limit), "rate", float(deviation[0])


def _seconds_at(record: StaticRecord, index: int, rate_hz: float) -> float:
    """When the record's reading ``index`` was taken, in seconds from its first (its own
    time where it has one: gaps before it counted), to 0.1 s."""
    times = record.times_s
    if times is not None and times.size > int(index):
        return round(float(times[int(index)] - times[0]), 1)
    return round(int(index) / rate_hz, 1)


def prepare_record(
    record: StaticRecord, rate_hz: float | None, *, max_tau_s: float | None = None
) -> PreparedRecord:
    """Gaps, spikes and warm-up dealt with; the rate from the times where none is given
    (the mean step of the longest stretch without a gap: a logger's clock stepping 10.0 or
    10.1 ms gives its mean rate, not the median step's).

    Parameters
    ----------
    record : StaticRecord
        The record as read (rates in °/h).
    rate_hz : float or None
        The sample rate (Hz); None takes it from the times' median step.
    max_tau_s : float, optional
        The longest τ (s) asked for: refused when the record (after trimming) is shorter
        than 2·τ, a note when shorter than 10·τ.

    Returns
    -------
    PreparedRecord
        The rates to analyse, the rate, and notes of what was done.

    Raises
    ------
    UserError
        No rate and no times, times that do not increase, or a record too short.

    References
    ----------
    IEEE Std 952-1997, annex C (test procedure: warm-up, temperature); lab-reference §6.
    """
    values = np.asarray(record.values, dtype=float)
    temperatures = record.temperatures_c
    notes: list[dict] = []
    origin = 0  # the first kept reading's index in the record: times said are the record's
    coarse = None
    if record.times_s is not None and record.times_s.size > 2:
        coarse = _coarse_clock(np.asarray(record.times_s, float))
    if coarse is not None:
        stretch, counted, tick, gaps, missing = coarse
        rate_hz = rate_hz or counted
        kept = stretch.stop - stretch.start
        notes.append(
            _note("allan.note_coarse_clock", tick=f"{tick:g}", rate=f"{counted:.4g}", kept=kept)
        )
        if gaps:
            seconds = round(kept / rate_hz)
            notes.append(
                _note("allan.note_gaps", gaps=gaps, missing=missing, kept=kept, seconds=seconds)
            )
        values, origin = values[stretch], stretch.start
        temperatures = None if temperatures is None else temperatures[stretch]
    elif record.times_s is not None and record.times_s.size > 2:
        times = np.asarray(record.times_s, float)
        stretch, gaps, missing, interval, tied = _longest_stretch(times)
        if rate_hz is None:  # the mean step of the stretch: a clock may jitter by a tick
            rate_hz = sample_rate_hz(times[stretch])
            if not math.isfinite(rate_hz):
                rate_hz = 1.0 / interval
        if tied:
            notes.append(_note("allan.note_tied_stamps", n=tied))
        if gaps:
            kept = stretch.stop - stretch.start
            notes.append(
                _note(
                    "allan.note_gaps",
                    gaps=gaps,
                    missing=missing,
                    kept=kept,
                    seconds=round(kept / rate_hz),
                )
            )
            values, origin = values[stretch], stretch.start
            temperatures = None if temperatures is None else temperatures[stretch]
    if rate_hz is None:
        raise UserError("allan.no_rate")
    if not (rate_hz > 0 and math.isfinite(rate_hz)):
        raise UserError("allan.bad_rate")
    starts, ends = disturbances(values, rate_hz)
    if starts.size:
        stretch = longest_between(starts, ends, values.size)
        kept = stretch.stop - stretch.start
        notes.append(
            _note(
                "allan.note_disturbances",
                n=int(starts.size),
                seconds=round(float(np.sum(ends - starts)) / rate_hz, 1),
                first_s=_seconds_at(record, origin + starts[0], rate_hz),
                kept=kept,
                kept_s=round(kept / rate_hz),
            )
        )
        values, origin = values[stretch], origin + stretch.start
        temperatures = None if temperatures is None else temperatures[stretch]
    mended = mend_lost_readings(values)
    if mended.gaps:
        kept = mended.stretch.stop - mended.stretch.start
        notes.append(
            _note(
                "allan.note_gaps",
                gaps=mended.gaps,
                missing=mended.missing,
                kept=kept,
                seconds=round(kept / rate_hz),
            )
        )
        temperatures = None if temperatures is None else temperatures[mended.stretch]
    values, origin = mended.values, origin + mended.stretch.start
    if mended.mended.size:
        notes.append(
            _note(
                "allan.note_lost_mended",
                n=int(mended.mended.size),
                first_s=_seconds_at(record, origin + mended.mended[0], rate_hz),
            )
        )
    if values.size >= 32:
        values, spikes = _despike(values)
        if spikes.size:
            notes.append(
                _note(
                    "allan.note_spikes",
                    n=int(spikes.size),
                    first_s=_seconds_at(record, origin + spikes[0], rate_hz),
                )
            )
        end, seen_by, size = _warm_up_end(values, temperatures)
        if end:
            notes.append(
                _note(
                    f"allan.note_trimmed_{seen_by}",
                    seconds=round(end / rate_hz),
                    change=f"{abs(size):.3g}",
                )
            )
            values = values[end:]
    record_s = values.size / rate_hz
    if max_tau_s is not None:
        if record_s < 2.0 * max_tau_s:
            raise UserError(
                "allan.too_short_for_tau",
                seconds=round(record_s),
                tau=max_tau_s,
                minimum=round(2 * max_tau_s),
            )
        if record_s < 10.0 * max_tau_s:
            notes.append(
                _note(
                    "allan.note_few_stretches",
                    ratio=f"{record_s / max_tau_s:.1f}",
                    tau=max_tau_s,
                )
            )
    return PreparedRecord(values, float(rate_hz), notes)
