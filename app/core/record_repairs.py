"""A static record's lost and disturbed readings: a logger's NaN for a reading it lost,
mended from its neighbours when the run is short and cut out as a gap when it is long;
a disturbance -- the gyro or its table knocked, a saturated output: readings far from the
record's level for longer than a spike -- cut out, the longest stretch without one kept.
Used by :func:`app.core.record_preparation.prepare_record`; joining across a gap or a
disturbance would fake a correlation (IEEE Std 952-1997, annex C; NIST SP 1065 §5).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from app.core.exceptions import UserError

SPIKE_LIMIT = 10.0  # robust σ from the level beyond which a reading is far
MAX_MENDED_RUN = 4  # lost readings in a row mended from their neighbours: half the median's
# the blocks whose medians draw the level a disturbance stands off: two minutes or more (a
# knock lasts seconds; a warm-up bends little within one), at most 256 of them
BURST_BLOCK_S = 120.0
MAX_BURST_BLOCKS = 256


def _runs(flags: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where each run of True starts, and where it ends (one past its last)."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], flags.astype(np.int8), [0]])))
    return edges[0::2], edges[1::2]


def longest_between(starts: np.ndarray, ends: np.ndarray, size: int) -> slice:
    """The longest stretch of ``size`` readings that holds none of the runs given.

    Parameters
    ----------
    starts, ends : numpy.ndarray
        Each run's first index and its end (one past its last), in order.
    size : int
        The readings in all.

    Returns
    -------
    slice
        The longest stretch between, before or after the runs (the first if tied).
    """
    begins = np.concatenate([[0], ends])
    stops = np.concatenate([starts, [size]])
    widest = int(np.argmax(stops - begins))
    return slice(int(begins[widest]), int(stops[widest]))


def reading_step(values: np.ndarray) -> float:
    """The smallest step between the readings' values (their quantisation), or 0.

    Parameters
    ----------
    values : numpy.ndarray
        The readings (the first 100,000 are looked at; NaN left out).

    Returns
    -------
    float
        The least difference between two distinct values; 0 when all are one value.
    """
    distinct = np.unique(values[: min(values.size, 100_000)])
    distinct = distinct[np.isfinite(distinct)]
    return float(np.min(np.diff(distinct))) if distinct.size > 1 else 0.0


def disturbances(values: np.ndarray, rate_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """Runs of readings far from the record's level for longer than a spike: the gyro or
    its table knocked, a saturated output.

    The level is the median of each block of ``BURST_BLOCK_S`` seconds or more (at most
    ``MAX_BURST_BLOCKS`` blocks), drawn as a line through the blocks' middles: a run
    shorter than half a block does not move it, a drift or a warm-up it follows.  A
    reading is far when it is more than ``SPIKE_LIMIT`` robust σ (1.4826·MAD of every
    reading's distance from the line, at least one reading step) from it.  A run of more
    than ``MAX_MENDED_RUN`` far readings is a disturbance, widened by ``MAX_MENDED_RUN``
    readings each side for its edges; shorter runs are left to the spike filter, and runs
    in the first two blocks -- where a warm-up bends away from the line most -- to the
    warm-up trim.

    Parameters
    ----------
    values : numpy.ndarray
        The rates (°/h), NaN where a reading was lost.
    rate_hz : float
        The sample rate (Hz).

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        Each disturbance's first index and its end (one past its last), widened.
    """
    none = (np.zeros(0, dtype=int), np.zeros(0, dtype=int))
    size = max(8, values.size // MAX_BURST_BLOCKS, int(round(BURST_BLOCK_S * rate_hz)))
    count = values.size // size
    if count < 4:
        return none
    blocks = values[: size * count].reshape(count, size)
    with np.errstate(all="ignore"):
        if np.any(np.all(~np.isfinite(blocks), axis=1)):
            return none  # a block lost whole: its gap, not a level, is what it shows
        medians = np.nanmedian(np.where(np.isfinite(blocks), blocks, np.nan), axis=1)
        middles = np.arange(count) * size + (size - 1) / 2.0
        distance = np.abs(values - np.interp(np.arange(values.size), middles, medians))
    scale = max(1.4826 * float(np.nanmedian(distance)), reading_step(values))
    if not scale > 0:
        return none
    with np.errstate(invalid="ignore"):
        far = distance > SPIKE_LIMIT * scale
    starts, ends = _runs(far)
    keep = ((ends - starts) > MAX_MENDED_RUN) & (starts >= 2 * size)
    starts = np.maximum(starts[keep] - MAX_MENDED_RUN, 0)
    ends = np.minimum(ends[keep] + MAX_MENDED_RUN, values.size)
    if starts.size > 1:  # widened runs that now touch are one
        joined = np.concatenate([[True], starts[1:] > ends[:-1]])
        starts = starts[joined]
        ends = np.maximum.reduceat(ends, np.flatnonzero(joined))
    return starts, ends


@dataclass(frozen=True)
class Mended:
    """A record's lost readings dealt with: the stretch kept, and what was done."""

    stretch: slice  # the longest stretch without a run of more than MAX_MENDED_RUN
    values: np.ndarray  # its readings, each lost one mended
    mended: np.ndarray  # the indices (in the stretch) of the readings mended
    gaps: int  # the longer runs, cut out
    missing: int  # the readings those runs lost


def mend_lost_readings(values: np.ndarray) -> Mended:
    """The readings that are not finite numbers: short runs mended, long ones cut out.

    A run of at most ``MAX_MENDED_RUN`` lost readings is replaced by the straight line
    between the readings either side (at an end, the nearest reading): as a spike is by
    its neighbours' median, the record's timeline kept.  A longer run is a gap: joined
    across, it would fake a correlation, so the longest stretch without one is kept.

    Parameters
    ----------
    values : numpy.ndarray
        The rates, NaN or ±inf where a reading was lost.

    Returns
    -------
    Mended
        The stretch kept, its readings mended, and the counts to say.

    Raises
    ------
    UserError
        ``readings.not_finite`` when no stretch holds two readings.
    """
    lost = ~np.isfinite(values)
    if not lost.any():
        return Mended(slice(0, values.size), values, np.zeros(0, dtype=int), 0, 0)
    starts, ends = _runs(lost)
    long = (ends - starts) > MAX_MENDED_RUN
    stretch = longest_between(starts[long], ends[long], values.size)
    kept = values[stretch]
    gone = np.flatnonzero(~np.isfinite(kept))
    there = np.flatnonzero(np.isfinite(kept))
    if there.size < 2:
        raise UserError("readings.not_finite")
    kept = kept.copy()
    kept[gone] = np.interp(gone, there, kept[there])
    return Mended(stretch, kept, gone, int(long.sum()), int(np.sum((ends - starts)[long])))
