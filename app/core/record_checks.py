"""Checks of one position's record: gaps (readings the gyro produced that never arrived)
and a gyro still warming up (its case temperature changing while recording)."""

from __future__ import annotations

import math

import numpy as np


def record_gaps(times_s: np.ndarray) -> tuple[int, int]:
    """Where a timed record skips readings, and how many it skips.

    The sampling interval is taken as the median time step, T = median(Δtᵢ).  A step of
    k·T (k ≥ 2 after rounding, i.e. Δtᵢ ≥ 1.5·T) means k − 1 readings are missing there;
    steps shorter than that are clock jitter, not gaps.

    Parameters
    ----------
    times_s : numpy.ndarray
        Each reading's time in seconds, in recording order.

    Returns
    -------
    gaps : int
        The number of places where readings are missing.
    missing : int
        How many readings are missing there in all.
    """
    times = np.asarray(times_s, dtype=float)
    if times.size < 3:
        return 0, 0
    steps = np.diff(times)
    interval = _median(steps)
    if not np.isfinite(interval) or interval <= 0:
        return 0, 0
    multiples = np.rint(steps / interval)
    skipped = multiples[multiples >= 2] - 1
    return int(skipped.size), int(skipped.sum())


def sample_rate_hz(times_s: np.ndarray) -> float:
    """The mean sample rate of a timed record, over its steps that are neither gaps nor
    tied stamps.

    With T = median(Δtᵢ), the steps kept are 0 < Δtᵢ < 1.5·T (as :func:`record_gaps`
    counts gaps), and f = (number kept) / Σ(kept Δtᵢ).  A logger's clock that steps 10.0 or
    10.1 ms has the mean rate of its readings, 1 / 10.07 ms, where 1 / median(Δt) would be
    0.3 % off -- as much error in a rate taken from angle increments × f.

    Parameters
    ----------
    times_s : numpy.ndarray
        Each reading's time in seconds, in recording order.

    Returns
    -------
    float
        The rate in Hz; NaN where the times have no rising step.
    """
    steps = np.diff(np.asarray(times_s, dtype=float))
    interval = _median(steps[steps > 0]) if np.any(steps > 0) else math.nan
    if not (math.isfinite(interval) and interval > 0):
        return math.nan
    kept = steps[(steps > 0) & (steps < 1.5 * interval)]
    return kept.size / float(np.sum(kept))


WARM_UP_LIMIT_C = 1.0


def warm_up_change(temperatures_c: np.ndarray) -> float | None:
    """How far the case temperature moved while recording, when that is a warm-up.

    A FOG's bias follows its temperature (the Shupe effect and the scale of the source's
    wavelength), so a record over which the case temperature spans more than
    ``WARM_UP_LIMIT_C`` = 1 °C, max(T) − min(T) > 1 °C, was taken during warm-up.

    Parameters
    ----------
    temperatures_c : numpy.ndarray
        The case temperature with each reading, in °C.

    Returns
    -------
    float or None
        max(T) − min(T) in °C when it exceeds the limit, else None.
    """
    temperatures = np.asarray(temperatures_c, dtype=float)
    if temperatures.size < 2:
        return None
    change = float(temperatures.max() - temperatures.min())
    return change if change > WARM_UP_LIMIT_C else None


SPIKE_LIMIT = 6.0  # robust σ
MAD_TO_SIGMA = 1.4826  # 1/Φ⁻¹(3/4): the MAD of normal readings is 0.6745 σ
_SAMPLED = 16_384  # readings looked at to bracket the median of a long record


def _median(x: np.ndarray) -> float:
    """``np.median`` of a 1-d array, the same value: by a sort up to 4,096 readings (a
    position's usual record), where ``np.median``'s own overhead (≈ 9 µs) is most of it
    (10 readings: 0.8 against 10.6 µs; 600: 2.1 against 10.0; 4,096: 12.7 against 17.2)."""
    if x.size > 4096 or x.size == 0:
        return float(np.median(x))
    ordered = np.sort(x)
    if np.isnan(ordered[-1]):  # NaN sorts last; np.median gives NaN
        return math.nan
    return float((ordered[(x.size - 1) // 2] + ordered[x.size // 2]) / 2)


def count_spikes(values: np.ndarray, limit: float = SPIKE_LIMIT) -> int:
    """The number of readings further than ``limit`` robust σ from the record's median.

    With m = median(x) and the robust σ̂ = 1.4826·median(|xᵢ − m|) (the MAD scaled to σ
    for normal noise; Rousseeuw & Croux 1993), a spike is a reading with
    |xᵢ − m| > limit·σ̂.  No spikes are counted when σ̂ = 0.

    The count is exact.  A long record (the bridge's or an upload's 10⁶ readings) is first
    tried without the two full medians: the median is bracketed, m ∈ [m₋, m₊], from an
    evenly spaced sample and the bracket certified by counting (#{x < m₋} ≤ k₁ and
    #{x ≤ m₊} ≥ k₂ + 1 for the middle ranks k₁ = ⌊(n−1)/2⌋, k₂ = ⌊n/2⌋).  The smallest σ̂
    that would leave every reading inside is a = max(max x − m₋, m₊ − min x)/(1.4826·limit);
    if #{m₋ − a′ ≤ x ≤ m₊ + a′} ≤ k₁ for a′ = a/1.4826, fewer than half the readings lie
    within a′ of any m in the bracket, so median|x − m| > a′, σ̂ > a and no reading is a
    spike.  Anything else (spikes, quantised or odd records) is counted the direct way.

    Parameters
    ----------
    values : numpy.ndarray
        One position's readings (finite).
    limit : float
        The spike limit in robust σ.

    Returns
    -------
    int
        How many readings lie beyond the limit.
    """
    x = np.asarray(values, dtype=float).ravel()
    n = x.size
    if n < 2:
        return 0
    if n >= 4 * _SAMPLED and _certainly_none(x, limit):
        return 0
    median = _median(x)
    deviation = np.abs(x - median)
    sigma = MAD_TO_SIGMA * _median(deviation)
    return int(np.count_nonzero(deviation > limit * sigma)) if sigma > 0 else 0


def _certainly_none(x: np.ndarray, limit: float) -> bool:
    """Whether the bracket argument of :func:`count_spikes` proves there is no spike."""
    n = x.size
    low_rank, high_rank = (n - 1) // 2, n // 2
    sample = np.sort(x[:: n // _SAMPLED])
    middle, spread = sample.size // 2, int(4 * np.sqrt(sample.size)) // 2 + 1
    m_low = float(sample[max(middle - spread, 0)])
    m_high = float(sample[min(middle + spread, sample.size - 1)])
    if not (
        np.count_nonzero(x < m_low) <= low_rank and np.count_nonzero(x <= m_high) >= high_rank + 1
    ):
        return False
    smallest, largest = float(x.min()), float(x.max())
    if not (np.isfinite(smallest) and np.isfinite(largest)):
        return False
    half_width = max(largest - m_low, m_high - smallest) / (MAD_TO_SIGMA * limit)
    if not half_width > 0:
        return False
    near = np.count_nonzero((x >= m_low - half_width) & (x <= m_high + half_width))
    return near <= low_rank
