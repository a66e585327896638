"""The dwell per position to recommend: the four-position heading σ against dwell, from a
noise model (:func:`recommended_dwell`) or from an Allan curve where no model fits it
(:func:`curve_dwell`), its minimum, whether the minimum lies beyond the dwells considered,
and the shortest dwell within 10 % of the best (lab-reference §3, §6; IEEE Std 952-1997,
annex C).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from app.core.noise_model import GyroNoise, four_position_sigma

LAB_DWELL_S = (5.0, 1800.0)  # the lab's shortest sensible and longest allowed dwell
DWELL_GRID_S = np.geomspace(0.01, 1.0e6, 8 * 24 + 1)  # 24 per decade: every caller's grid
NEAR_BEST = 1.1  # "within 10 % of the best σ"


@dataclass(frozen=True)
class DwellAdvice:
    """Four-position heading σ against dwell (for an amplitude H of 1 °/h: divide by H).

    ``recommended_s`` minimises σ within the span; ``lower_bound`` says σ is still falling
    at the span's end (``limit``: "record", the record's longest τ, or "lab", the longest
    dwell the lab allows), so the optimum lies beyond it; ``near_best_s`` is the shortest
    dwell whose σ is within 10 % of the best; ``levels_off`` says σ falls, at the span's
    end, only towards the flicker floor: the model holds no term that makes it rise again
    (rate random walk, a Gauss–Markov bias, a ramp; a periodic bias only ripples it), so
    there is no best dwell beyond to find; ``swing_period_s`` is a resolved periodic bias's
    period P, whose whole multiples average it out of every position's mean."""

    dwell_s: np.ndarray
    sigma: np.ndarray  # the full noise model (or the curve, when no model fits)
    white_sigma: np.ndarray | None  # angle random walk alone
    recommended_s: float
    lower_bound: bool
    near_best_s: float
    limit: str
    source: str = "model"  # "model" or "curve"
    levels_off: bool = False
    swing_period_s: float | None = None  # a resolved periodic bias's P: whole periods cancel it

    def to_json(self) -> dict:
        return {
            "recommended_s": self.recommended_s,
            "lower_bound": self.lower_bound,
            "near_best_s": self.near_best_s,
            "limit": self.limit,
            "source": self.source,
            "levels_off": self.levels_off,
            "swing_period_s": self.swing_period_s,
        }


def _advice(dwell, sigma, white, limit, source) -> DwellAdvice:
    best = int(np.argmin(sigma))
    lower_bound = best == dwell.size - 1 and dwell.size > 1 and sigma[-1] < sigma[-2]
    near = int(np.flatnonzero(sigma <= NEAR_BEST * sigma[best])[0])
    return DwellAdvice(
        dwell,
        sigma,
        white,
        float(dwell[best]),
        bool(lower_bound),
        float(dwell[near]),
        limit,
        source,
    )


def dwell_grid(span_s: tuple[float, float]) -> np.ndarray:
    """The dwells considered: the fixed grid (24 per decade) inside ``span_s`` and its two
    ends -- the same dwells for every caller, so the explorer, the Allan page and the CLI
    land on the same number.

    Parameters
    ----------
    span_s : (float, float)
        The shortest and longest dwell (s).

    Returns
    -------
    numpy.ndarray
        The dwells (s), increasing.
    """
    low, high = float(span_s[0]), float(span_s[1])
    inside = DWELL_GRID_S[(low * (1 + 1e-9) < DWELL_GRID_S) & (high * (1 - 1e-9) > DWELL_GRID_S)]
    return np.unique(np.concatenate([[low], inside, [high]]))


def recommended_dwell(
    noise: GyroNoise, rate_hz: float, span_s: tuple[float, float] = LAB_DWELL_S, limit: str = "lab"
) -> DwellAdvice:
    """The dwell per position that minimises the four-position heading σ.

    σ_A(T) = √((v_x + v_y)/2)/H for four back-to-back positions of dwell T (the noise
    model's covariance of the four means, :func:`four_position_sigma`), minimised over the
    fixed dwell grid inside ``span_s``.  White noise falls as 1/√T, the flicker floor stays,
    rate random walk, a Gauss–Markov bump and a rate ramp rise (a ramp R moves
    x = (ω1 − ω3)/2 and y = (ω2 − ω4)/2 by R·T each, T in hours): with only white and
    flicker noise σ keeps falling, the optimum lies beyond the span, and the advice says so
    (``lower_bound``; ``levels_off`` with a flicker floor: σ only approaches it) and gives
    the shortest dwell within 10 % of the best σ.  The heading σ scales as 1/H, so the
    choice does not depend on the latitude.

    Parameters
    ----------
    noise : GyroNoise
        The gyro's noise terms.
    rate_hz : float
        Sample rate (Hz).
    span_s : (float, float)
        The dwells to consider (s): the lab's range, or a record's τ range.
    limit : {"lab", "record"}
        What the span's end is, for the words of a lower bound.

    Returns
    -------
    DwellAdvice
        The heading σ against dwell, the recommended dwell, whether it is a lower bound,
        and the shortest dwell within 10 % of the best.

    References
    ----------
    lab-reference §3 and §6; IEEE Std 952-1997, annex C.
    """
    dwell = dwell_grid(span_s)
    white_noise = GyroNoise(arw_deg_rt_h=noise.arw_deg_rt_h)
    sigma = np.array([four_position_sigma(noise, rate_hz, t, 1.0) for t in dwell])
    white = np.array([four_position_sigma(white_noise, rate_hz, t, 1.0) for t in dwell])
    advice = _advice(dwell, sigma, white, limit, "model")
    # a swing's share of a position mean falls as 1/T (whole periods average it out): it
    # makes σ ripple, never rise for good, so it leaves a σ that levels off as it is
    rises = noise.rrw_deg_h_rt_h > 0 or noise.markov_sigma_deg_h > 0 or noise.ramp_deg_h_per_h > 0
    if advice.lower_bound and noise.bias_instability_deg_h > 0 and not rises:
        advice = replace(advice, levels_off=True)
    if noise.has_sinusoid:
        advice = replace(advice, swing_period_s=noise.sine_period_s)
    return advice


def curve_dwell(taus_s: np.ndarray, adev: np.ndarray) -> DwellAdvice:
    """Dwell advice from the Allan curve itself, where no noise model fits it: the heading
    σ of four back-to-back positions follows the Allan deviation at τ = T, so the best dwell
    sits at the curve's minimum (lab-reference §6).

    Parameters
    ----------
    taus_s, adev : numpy.ndarray
        The curve: τ (s) and σ(τ) (°/h).

    Returns
    -------
    DwellAdvice
        With ``source`` "curve" and ``limit`` "record".
    """
    return _advice(np.asarray(taus_s, float), np.asarray(adev, float), None, "record", "curve")
