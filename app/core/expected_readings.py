"""Readings the station's gyro would make: one draw of its noise model at the counts a
group recorded, to show beside the group's own readings (lab-reference §6).

The n readings x_1 … x_n of one position, from a warm gyro at rest, are jointly normal
with covariance Cov(x_i, x_j) = C_ij, the covariance of the means over one-sample windows
(:meth:`GyroNoise.mean_covariance` of ``back_to_back([1]*n, f)``, warm-up left out: the
same model the scatter check uses).  A draw is x = L·z, L the Cholesky factor of C and z
standard normal; each position is its own draw about zero (the position's rate is left
out, as it is from the group's readings in the chart), rounded to the step the group
typed to (or the gyro's own output step)."""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

import numpy as np

from app.core.noise_model import GyroNoise, back_to_back

MAX_READINGS = 100  # readings per position drawn (and shown)


@lru_cache(maxsize=64)
def _factor(noise: GyroNoise, rate_hz: float, count: int) -> np.ndarray:
    cov = noise.mean_covariance(back_to_back([1] * count, rate_hz), warm_up=False)
    jitter = 1e-12 * max(float(np.trace(cov)) / count, 1e-30)
    return np.linalg.cholesky(cov + jitter * np.eye(count))


def expected_readings(
    noise: GyroNoise,
    rate_hz: float,
    counts: Sequence[int],
    step: float | None,
    seed: int,
) -> list[np.ndarray]:
    """One draw of each position's readings about zero from the gyro's noise model.

    Parameters
    ----------
    noise : GyroNoise
        The station's gyro.
    rate_hz : float
        Its readings per second.
    counts : sequence of int
        Readings per position (each capped at ``MAX_READINGS``).
    step : float or None
        The step (°/h) to round to: the group's typed step, else the gyro's own.
    seed : int
        The draw's seed (one session, one draw: the page does not change on reload).

    Returns
    -------
    list of numpy.ndarray
        Each position's readings (°/h) about zero.
    """
    rng = np.random.default_rng(seed)
    out = []
    for count in counts:
        count = int(min(max(count, 0), MAX_READINGS))
        if count == 0:
            out.append(np.zeros(0))
            continue
        draw = _factor(noise, float(rate_hz), count) @ rng.standard_normal(count)
        if step:
            draw = np.round(draw / step) * step
        out.append(draw)
    return out
