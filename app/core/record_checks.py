"""Checks of one position's record: gaps (readings the gyro produced that never arrived)
and a gyro still warming up (its case temperature changing while recording)."""

from __future__ import annotations

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
    interval = float(np.median(steps))
    if not np.isfinite(interval) or interval <= 0:
        return 0, 0
    multiples = np.rint(steps / interval)
    skipped = multiples[multiples >= 2] - 1
    return int(skipped.size), int(skipped.sum())


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
