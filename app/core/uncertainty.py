"""How uncertain each position mean is: the variances the fit propagates (lab-reference §3,
"Honest uncertainty beyond white noise").

Three models, named in every result as ``uncertainty_model``:

``"white"``
    Every position has two or more readings.  The mean of n readings with sample std s has
    standard error s/√n; with few readings the 68.27 % interval of Student's t with n − 1
    degrees of freedom is wider than ±s/√n, so the reported "1σ-equivalent" is

        σ_i = k(n_i − 1) · s_i/√n_i,   k(ν) = t_ν⁻¹(0.84134)

    (k(9) = 1.059, k(1) = 1.837, k → 1 for large n).  Readings that are all identical
    (s = 0) carry the quantisation floor σ_i = LSB/√12, the LSB being the data's step
    (the smallest gap between distinct readings of a position) or, when every position
    is constant, the resolution the numbers were written with.

``"closure"``
    One reading per position (the handout's "type the four averages"): four positions
    90° apart give the closure residual d = (ω1 + ω3 − ω2 − ω4)/2, whose std is the std
    σ of one position value -- a one-degree-of-freedom estimate, σ_i = k(1)·|d|.

``"allan"``
    The gyro's noise model is known (the simulator's preset, or an Allan characterisation):
    the covariance of the position means follows from it and the recording schedule
    (:mod:`app.core.noise_model`), correlated noise (bias instability, random walk)
    included where s²/n is over-confident.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

ONE_SIGMA = 0.6826894921370859  # the probability within ±1σ of a normal distribution
MAX_DECIMALS = 6


@lru_cache(maxsize=256)
@lru_cache(maxsize=256)
def t_factor(dof: int) -> float:
    """Half-width, in standard errors, of Student's t central 68.27 % interval.

    k(ν) = t_ν⁻¹((1 + 0.68269)/2); a standard error times k is the "1σ-equivalent" interval
    of a mean estimated from ν + 1 readings (k(9) = 1.06, k(1) = 1.84).

    Parameters
    ----------
    dof : int
        ν, the degrees of freedom (readings − 1), at least 1.

    Returns
    -------
    float
        k(ν).

    References
    ----------
    lab-reference §3 (honest uncertainty); GUM (JCGM 100:2008) G.3.
    """
    if dof < 1:
        raise ValueError("Student's t needs at least one degree of freedom")
    from scipy.stats import t as student_t  # imported when first needed: ~0.6 s

    return float(student_t.ppf(0.5 + ONE_SIGMA / 2, dof))


def reading_step(arrays: Sequence[np.ndarray]) -> float | None:
    """The quantisation step the data show.

    Sorting every record to find it (``np.unique``) is the one cost here that grows as
    n log n, so :func:`position_noise` asks for it only where it is used: a position whose
    readings are all identical, or one reading per position.

    Parameters
    ----------
    arrays : sequence of numpy.ndarray
        Every position's readings (°/h).

    Returns
    -------
    float or None
        The smallest gap between distinct readings within any one position; None when
        every position is constant.
    """
    gaps = []
    for array in arrays:
        distinct = np.unique(array)
        if distinct.size > 1:
            gaps.append(float(np.min(np.diff(distinct))))
    return min(gaps) if gaps else None


def written_resolution(arrays: Sequence[np.ndarray]) -> float:
    """The resolution the readings were written to: 10⁻ᵈ for the fewest decimals d (≤ 6)
    that write every reading exactly.

    Parameters
    ----------
    arrays : sequence of numpy.ndarray
        Every position's readings (°/h).

    Returns
    -------
    float
        10⁻ᵈ (°/h).
    """
    values = np.concatenate([np.asarray(a, dtype=float) for a in arrays])
    for decimals in range(MAX_DECIMALS + 1):
        scaled = values * 10.0**decimals
        if np.all(np.abs(scaled - np.round(scaled)) <= 1e-6 * np.maximum(1.0, np.abs(scaled))):
            return 10.0**-decimals
    return 10.0**-MAX_DECIMALS


def quantisation_floor(arrays: Sequence[np.ndarray]) -> float:
    """The floor of a position mean's σ set by the readings' resolution: LSB/√12.

    Parameters
    ----------
    arrays : sequence of numpy.ndarray
        Every position's readings (°/h).

    Returns
    -------
    float
        LSB/√12 (°/h), LSB the step between the readings (or their written resolution).

    References
    ----------
    lab-reference §3; GUM (JCGM 100:2008) F.2.2.1 (resolution of a digital indication).
    """
    step = reading_step(arrays)
    lsb = step if step is not None else written_resolution(arrays)
    return lsb / math.sqrt(12.0)


def closure_residual(angles_deg: np.ndarray, means: np.ndarray) -> float | None:
    """The four-position closure d = (ω1 + ω3 − ω2 − ω4)/2.

    For four positions 90° apart the sinusoid predicts ω1 + ω3 = ω2 + ω4 = 2b, so d is
    pure noise: its spread estimates the means' σ when each position has one reading.

    Parameters
    ----------
    angles_deg : numpy.ndarray
        The positions' angles (°).
    means : numpy.ndarray
        The positions' mean readings (°/h).

    Returns
    -------
    float or None
        d (°/h); None unless there are four positions 90° apart (either way round).

    References
    ----------
    lab-reference §3 (closure).
    """
    if angles_deg.size != 4:
        return None
    steps = [float(step) for step in np.diff(angles_deg)]

    def close(value: float, target: float, atol: float) -> bool:  # numpy.allclose's test
        return abs(value - target) <= atol + 1e-5 * abs(target)  # (False for NaN)

    if not all(close(abs(s), 90.0, 1e-6) and close(s, steps[0], 1e-8) for s in steps):
        return None
    return float((means[0] + means[2] - means[1] - means[3]) / 2)


@dataclass(frozen=True)
class PositionNoise:
    """The covariance of the position means (°/h)² and the model that gave it."""

    cov: np.ndarray
    model: str  # "white" | "closure" | "allan"

    @property
    def variances(self) -> np.ndarray:
        return np.diag(self.cov).copy()

    @property
    def sigmas(self) -> np.ndarray:
        """The 1σ(-equivalent) of each position mean."""
        return np.sqrt(np.maximum(self.variances, 0.0))

    @classmethod
    def independent(cls, sigmas: Sequence[float], model: str) -> PositionNoise:
        return cls(np.diag(np.asarray(sigmas, dtype=float) ** 2), model)


def position_noise(
    arrays: Sequence[np.ndarray],
    angles_deg: np.ndarray,
    *,
    position_cov: np.ndarray | None = None,
    stds: Sequence[float | None] | None = None,
) -> PositionNoise | None:
    """The covariance model of the position means, or None when nothing estimates it.

    In order of preference: a known noise model's ``position_cov`` (model "allan"); the
    readings' own scatter, s_i²/n_i scaled by Student's k(n_i − 1)² and floored at LSB²/12
    (model "white"); for one reading per position, the closure residual's d² on the
    diagonal (model "closure").  See the module's docstring.

    Parameters
    ----------
    arrays : sequence of numpy.ndarray
        Every position's readings (°/h).
    angles_deg : numpy.ndarray
        The positions' angles (°).
    position_cov : numpy.ndarray, optional
        Σ from a known noise model ((°/h)²).
    stds : sequence of float, optional
        Each position's sample standard deviation (ddof = 1) when already known
        (``sinusoid.position_stats``), so that a long record is not read twice.

    Returns
    -------
    PositionNoise or None
        Σ ((°/h)²) and the name of its model.

    References
    ----------
    lab-reference §3; IEEE Std 952-1997 (the noise terms behind ``position_cov``).
    """
    if position_cov is not None:
        return PositionNoise(np.asarray(position_cov, dtype=float), "allan")
    counts = [array.size for array in arrays]
    if min(counts) >= 2:
        sigmas = []
        floor = None  # found only when needed: it sorts every record (reading_step)
        for k, array in enumerate(arrays):
            if np.ptp(array) == 0.0:  # all identical: rounding is the only error left
                floor = quantisation_floor(arrays) if floor is None else floor
                sigmas.append(floor)
            else:
                std = float(array.std(ddof=1)) if stds is None or stds[k] is None else stds[k]
                sigmas.append(t_factor(array.size - 1) * std / math.sqrt(array.size))
        return PositionNoise.independent(sigmas, "white")
    means = np.array([float(array.mean()) for array in arrays])
    d = closure_residual(angles_deg, means)
    if d is None:
        return None
    sigma = max(t_factor(1) * abs(d), quantisation_floor(arrays))
    return PositionNoise.independent([sigma] * len(arrays), "closure")
