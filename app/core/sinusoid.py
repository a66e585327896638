"""The fit behind both parts: N positions' readings → the sinusoid a·cos α + c·sin α + b.

Model (lab-reference §3).  Position i has a known angle α_i (heading part: axis azimuth
relative to position 1, clockwise positive seen from above; latitude part: axis elevation
e_i in the meridian plane, 0° = north horizon, 90° = up).  Every reading is

    ω = a·cos α + c·sin α + b + noise

and (a, c, b) come from least squares over all samples.  With n_i samples and mean m_i at
position i this is the weighted fit of the means, β = (XᵀNX)⁻¹XᵀN·m, N = diag(n_i), so
the 1σ covariance propagated from the positions' standard errors s_i/√n_i is
Cov β = L·diag(s_i²/n_i)·Lᵀ with L = (XᵀNX)⁻¹XᵀN.  With five or more positions recorded
on one clock a linear bias drift ḃ·t is fitted as a fourth term.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from app.core.exceptions import UserError
from app.core.uncertainty import PositionNoise, closure_residual, position_noise
from app.core.units import MAX_RATE_DEG_H

SIGNIFICANCE = 3.0  # an amplitude below 3σ is not a measurement of anything
ROTATIONS = ("ccw", "cw")


MAX_ANGLE_DEG = 3600.0  # ten turns of a dial: anything beyond is a typing mistake


@dataclass(frozen=True)
class PositionStats:
    """Per-position summary: count, mean, sample std (ddof=1) and standard error."""

    n: int
    mean: float
    std: float | None
    sem: float | None


@dataclass(frozen=True)
class SinusoidFit:
    a: float
    c: float
    b: float
    cov: np.ndarray | None  # 3×3 covariance of (a, c, b), None when nothing estimates it
    angles_deg: np.ndarray
    stats: tuple[PositionStats, ...]
    noise: PositionNoise | None = None  # the position means' 1σ and its model
    drift: float | None = None  # ḃ (°/h per hour) when the schedule lets it be fitted

    @property
    def means(self) -> np.ndarray:
        return np.array([s.mean for s in self.stats])

    @property
    def drift_sigma(self) -> float | None:
        if self.drift is None or self.cov is None or self.cov.shape[0] < 4:
            return None
        return float(math.sqrt(max(self.cov[3, 3], 0.0)))

    @property
    def bias_sigma(self) -> float | None:
        """1σ of the bias b, √(Cov β)_bb; for four positions 90° apart with independent
        means b = (m1 + m2 + m3 + m4)/4, so σ_b = √(σ1² + σ2² + σ3² + σ4²)/4."""
        if self.cov is None:
            return None
        return float(math.sqrt(max(float(self.cov[2, 2]), 0.0)))

    @property
    def position_sigmas(self) -> list[float] | None:
        """The 1σ(-equivalent) of each position mean that the fit propagates."""
        return None if self.noise is None else [float(x) for x in self.noise.sigmas]

    @property
    def uncertainty_model(self) -> str | None:
        return None if self.noise is None else self.noise.model

    @functools.cached_property  # read by the fit's σ, the drift check and the page
    def closure_residual(self) -> float | None:
        return closure_residual(self.angles_deg, self.means)

    @functools.cached_property
    def closure_sigma(self) -> float | None:
        """σ_d = √(wᵀΣw), w = (1, −1, 1, −1)/2: √(σ1² + σ2² + σ3² + σ4²)/2 for independent
        means, with their correlations under a noise model (None without four positions
        90° apart)."""
        if self.noise is None or self.closure_residual is None:
            return None
        weights = np.array([0.5, -0.5, 0.5, -0.5])
        return float(math.sqrt(max(float(weights @ self.noise.cov @ weights), 0.0)))

    @property
    def closure_consistent(self) -> bool | None:
        """|d| ≤ 3σ_d: the noise is what the σ assumes (None when d itself gave σ)."""
        sigma = self.closure_sigma
        if sigma is None or self.uncertainty_model == "closure" or sigma == 0:
            return None
        return abs(self.closure_residual) <= SIGNIFICANCE * sigma


def position_stats(samples: np.ndarray) -> PositionStats:
    """One position's count, mean, sample standard deviation and standard error.

    Parameters
    ----------
    samples : numpy.ndarray
        The position's readings (°/h).

    Returns
    -------
    PositionStats
        n, mean m = Σω/n, s (ddof = 1; None for one reading) and s/√n.
    """
    n = int(samples.size)
    mean = float(samples.mean())
    if n < 2:
        return PositionStats(n, mean, None, None)
    std = float(samples.std(ddof=1))
    return PositionStats(n, mean, std, std / math.sqrt(n))


def wrap180(angle_deg: float) -> float:
    """Wrap an angle to (−180°, 180°].

    Parameters
    ----------
    angle_deg : float
        Any angle (°).

    Returns
    -------
    float
        The same direction in (−180°, 180°].
    """
    wrapped = math.fmod(angle_deg, 360.0)
    if wrapped <= -180.0:
        wrapped += 360.0
    elif wrapped > 180.0:
        wrapped -= 360.0
    return wrapped


def wrap360(angle_deg: float) -> float:
    """Wrap an angle to [0°, 360°) (a tiny negative rounds to 0, never to 360).

    Parameters
    ----------
    angle_deg : float
        Any angle (°).

    Returns
    -------
    float
        The same direction in [0°, 360°).
    """
    wrapped = angle_deg % 360.0
    return 0.0 if wrapped >= 360.0 else wrapped


def heading_angles(
    n_positions: int, rotation: str = "ccw", start_deg: float = 0.0, step_deg: float = 90.0
) -> np.ndarray:
    """Axis azimuths relative to the reference, clockwise positive.

    Counter-clockwise turns give start, start − step, ...; clockwise turns give start,
    start + step, ... (the handout turns counter-clockwise by 90°).

    Parameters
    ----------
    n_positions : int
        How many positions.
    rotation : {"ccw", "cw"}
        The way the table is turned between positions.
    start_deg : float
        The dial angle of position 1 (°).
    step_deg : float
        The turn between positions (°), not a multiple of 360°.

    Returns
    -------
    numpy.ndarray
        α_i (°), one per position.
    """
    if rotation not in ROTATIONS:
        raise UserError(
            "rotation.unknown",
            rotation=rotation,
        )
    _check_schedule(start_deg, step_deg)
    sign = -1.0 if rotation == "ccw" else 1.0
    return start_deg + sign * step_deg * np.arange(n_positions)


def _check_schedule(start_deg: float, step_deg: float) -> None:
    """A start angle within ±3600° and a step within ±360° (finite), else a range message."""
    if not (math.isfinite(start_deg) and abs(start_deg) <= MAX_ANGLE_DEG):
        raise UserError(
            "angles.start_out_of_range",
            limit=MAX_ANGLE_DEG,
        )
    if not (math.isfinite(step_deg) and abs(step_deg) <= 360.0):
        raise UserError("angles.step_out_of_range")


def elevation_angles(
    n_positions: int, start_deg: float = 0.0, step_deg: float = 90.0
) -> np.ndarray:
    """Axis elevations in the meridian plane: start, start + step, ... (0° north, 90° up).

    Parameters
    ----------
    n_positions : int
        How many positions.
    start_deg : float
        Elevation of position 1 (°).
    step_deg : float
        The turn between positions (°), not a multiple of 360°.

    Returns
    -------
    numpy.ndarray
        e_i (°), one per position.
    """
    _check_schedule(start_deg, step_deg)
    return start_deg + step_deg * np.arange(n_positions)


def _clean_positions(positions: Sequence[Sequence[float]]) -> list[np.ndarray]:
    arrays = []
    for index, samples in enumerate(positions, start=1):
        try:
            array = np.asarray(samples, dtype=float).ravel()
        except (TypeError, ValueError) as error:
            raise UserError(
                "readings.not_numbers",
                position=index,
            ) from error
        if array.size == 0:
            raise UserError("readings.empty_position", position=index)
        # two passes that allocate nothing (NaN fails both comparisons); which check
        # failed is looked for only then
        if not (array.min() >= -MAX_RATE_DEG_H and array.max() <= MAX_RATE_DEG_H):
            if not np.all(np.isfinite(array)):
                raise UserError(
                    "readings.not_finite",
                    position=index,
                )
            raise UserError(
                "readings.out_of_range",
                position=index,
            )
        arrays.append(array)
    return arrays


def fit_sinusoid(
    positions: Sequence[Sequence[float]],
    angles_deg: Sequence[float],
    *,
    position_cov: np.ndarray | None = None,
    indexing_sigma_deg: float = 0.0,
    times_s: Sequence[Sequence[float]] | None = None,
) -> SinusoidFit:
    """Least-squares fit of ω = a·cos α + c·sin α + b over every sample.

    The weighted fit of the position means, β = (XᵀNX)⁻¹XᵀN·m with N = diag(n_i), and its
    covariance Cov β = L·Σ·Lᵀ, L = (XᵀNX)⁻¹XᵀN, propagated from the position means'
    covariance Σ (:func:`app.core.uncertainty.position_noise`: white noise with Student-t,
    the closure residual, or a known noise model's ``position_cov``).  An indexing error
    δ ~ N(0, σ_idx) at each stop after the first moves its reading by
    ∂ω/∂α·δ = (−a·sin α + c·cos α)·δ; that variance joins Σ's diagonal.  With ``times_s``
    and five or more positions a linear drift is fitted too,
    ω = a·cos α + c·sin α + b + ḃ·(t − t̄).

    Parameters
    ----------
    positions : sequence of sequences of float
        Each position's readings (°/h).
    angles_deg : sequence of float
        Each position's angle α_i (°); at least three different ones.
    position_cov : numpy.ndarray, optional
        Σ from a known noise model ((°/h)², one row per position).
    indexing_sigma_deg : float
        σ_idx (°).
    times_s : sequence of sequences of float, optional
        Each reading's time (s, one clock for the whole schedule).

    Returns
    -------
    SinusoidFit
        a, c, b (°/h), their covariance (None when nothing estimates it), the angles, each
        position's statistics and noise, and the drift ḃ (°/h per hour) when fitted.

    Raises
    ------
    UserError
        Empty or non-finite readings, too few or repeated angles, mismatched counts.

    References
    ----------
    lab-reference §3 (model, drift); Press et al., *Numerical Recipes*, §15.4 (linear least
    squares and the covariance of its parameters).
    """
    arrays = _clean_positions(positions)
    angles = np.asarray(angles_deg, dtype=float)
    if angles.shape != (len(arrays),):
        raise UserError(
            "readings.angle_count",
            positions=len(arrays),
            angles=int(angles.size),
        )
    if not np.all(np.isfinite(angles)):
        raise UserError("readings.angle_not_finite")
    distinct = np.unique(np.round(np.mod(angles, 360.0), 6) % 360.0)
    if distinct.size < 3:
        raise UserError(
            "readings.too_few_angles",
            distinct=int(distinct.size),
        )
    stats = tuple(position_stats(a) for a in arrays)
    counts = np.array([s.n for s in stats], dtype=float)
    means = np.array([s.mean for s in stats])
    radians = np.radians(angles)
    design = np.column_stack([np.cos(radians), np.sin(radians), np.ones_like(radians)])
    clock = _mean_times_h(times_s, arrays)
    if clock is not None:
        with_drift = np.column_stack([design, clock])
        drift_normal = with_drift.T @ (counts[:, None] * with_drift)
        if np.linalg.cond(drift_normal) < 1e10:
            design = with_drift
    normal = design.T @ (counts[:, None] * design)
    if np.linalg.cond(normal) > 1e12:
        raise UserError("readings.angles_degenerate")
    mapping = np.linalg.solve(normal, design.T * counts)  # L = (XᵀNX)⁻¹XᵀN
    a, c, b, *rest = mapping @ means
    noise = position_noise(arrays, angles, position_cov=position_cov, stds=[s.std for s in stats])
    if noise is not None and indexing_sigma_deg > 0:
        slope = -a * np.sin(radians) + c * np.cos(radians)  # ∂ω/∂α at each stop, per rad
        extra = (slope * math.radians(indexing_sigma_deg)) ** 2
        extra[0] = 0.0  # the first stop is the reference
        noise = PositionNoise(noise.cov + np.diag(extra), noise.model)
    cov = None if noise is None else mapping @ noise.cov @ mapping.T
    drift = float(rest[0]) if rest else None
    return SinusoidFit(float(a), float(c), float(b), cov, angles, stats, noise, drift)


MIN_POSITIONS_FOR_DRIFT = 5


def _mean_times_h(
    times_s: Sequence[Sequence[float]] | None, arrays: list[np.ndarray]
) -> np.ndarray | None:
    """Each position's mean time in hours from the schedule's mean (None when the times
    are missing, do not match the readings, or the schedule is too short for a drift)."""
    if times_s is None or len(arrays) < MIN_POSITIONS_FOR_DRIFT or len(times_s) != len(arrays):
        return None
    means = []
    for times, values in zip(times_s, arrays, strict=True):
        stamps = np.asarray(times, dtype=float).ravel()
        if stamps.size != values.size or not np.all(np.isfinite(stamps)):
            return None
        means.append(float(stamps.mean()))
    hours = np.asarray(means) / 3600.0
    return hours - hours.mean()
