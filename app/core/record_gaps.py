"""Gaps in a timed record: readings that a gyro produced but that never arrived."""

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
