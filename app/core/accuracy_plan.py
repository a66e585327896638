"""The accuracy planner: the 1σ of the heading, the latitude and the Earth rate that a
station's gyro gives for a dwell per position and a recording order, from its noise model,
before anything is recorded (lab-reference §3 and §6).

For positions recorded back to back, each for a dwell T, the noise model gives the
covariance Σ of the position means (:meth:`GyroNoise.mean_covariance`, the gyro warm).  The
fit of ω = a·cos α + c·sin α + b (+ ḃ·(t − t̄) for the symmetric order, whose point is to
cancel a linear drift) over the positions' angles α_i is β = L·m with
L = (XᵀX)⁻¹Xᵀ (equal counts), so Cov β = L·Σ·Lᵀ.  Then, from the fitted a and c:

* heading part, H = Ω·cos φ: A = atan2(c, a) up to the turn's sign, so, averaged over the
  unknown azimuth, σ_A = √((v_a + v_c)/2)/H rad;
* vertical part, a = Ω·cos φ and c = Ω·sin φ at the station's latitude:
  σ_φ = √(sin²φ·v_a + cos²φ·v_c − 2 sinφ cosφ·c_ac)/Ω rad and
  σ_Ω = √(cos²φ·v_a + sin²φ·v_c + 2 sinφ cosφ·c_ac) (°/h).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from app.core.dwell_advice import NEAR_BEST
from app.core.noise_model import GyroNoise, back_to_back

# the four stops 90° apart, and the orders they are recorded in (indices of the stops)
STOPS_DEG = (0.0, 90.0, 180.0, 270.0)
ORDERS: dict[str, tuple[int, ...]] = {
    "1234": (0, 1, 2, 3),
    "12344321": (0, 1, 2, 3, 3, 2, 1, 0),
}
PLAN_DWELLS_S = (10.0, 20.0, 30.0, 60.0, 120.0, 180.0, 300.0, 600.0, 900.0, 1200.0, 1800.0)


@dataclass(frozen=True)
class PlanPoint:
    """The expected 1σ of one plan: ``order`` recorded with ``dwell_s`` per position."""

    order: str
    dwell_s: float
    total_s: float  # recording time of the whole part (turns not counted)
    heading_sigma_deg: float
    latitude_sigma_deg: float
    earth_rate_sigma_deg_h: float

    def to_json(self) -> dict:
        return {
            "order": self.order,
            "dwell_s": self.dwell_s,
            "total_s": self.total_s,
            "heading_sigma_deg": self.heading_sigma_deg,
            "latitude_sigma_deg": self.latitude_sigma_deg,
            "earth_rate_sigma_deg_h": self.earth_rate_sigma_deg_h,
        }


def fit_covariance(noise: GyroNoise, rate_hz: float, dwell_s: float, order: str) -> np.ndarray:
    """Cov of the fitted (a, c, b[, ḃ]) for ``order`` recorded back to back, ``dwell_s`` each.

    Parameters
    ----------
    noise : GyroNoise
        The gyro's noise terms (IEEE 952).
    rate_hz : float
        Sample rate (Hz).
    dwell_s : float
        Recording time per position (s).
    order : str
        A key of :data:`ORDERS`.

    Returns
    -------
    numpy.ndarray
        L·Σ·Lᵀ, (°/h)²; the drift column is fitted for orders of five or more positions.
    """
    stops = ORDERS[order]
    count = max(1, int(round(dwell_s * rate_hz)))
    windows = back_to_back([count] * len(stops), rate_hz)
    sigma = noise.mean_covariance(windows, warm_up=False)
    angles = np.radians([STOPS_DEG[k] for k in stops])
    columns = [np.cos(angles), np.sin(angles), np.ones(len(stops))]
    if len(stops) >= 5:
        middles = np.array([w.start_s + w.length_s / 2 for w in windows])
        columns.append(middles - middles.mean())
    design = np.column_stack(columns)
    lift = np.linalg.solve(design.T @ design, design.T)
    return lift @ sigma @ lift.T


def plan_point(
    noise: GyroNoise,
    rate_hz: float,
    dwell_s: float,
    order: str,
    latitude_deg: float,
    earth_rate_deg_h: float,
) -> PlanPoint:
    """The expected 1σ of heading, latitude and Earth rate for one plan (module docstring).

    Parameters
    ----------
    noise : GyroNoise
        The gyro's noise terms.
    rate_hz : float
        Sample rate (Hz).
    dwell_s : float
        Recording time per position (s).
    order : str
        "1234" (four positions) or "12344321" (the symmetric eight).
    latitude_deg, earth_rate_deg_h : float
        The station's φ (°) and Ω (°/h).

    Returns
    -------
    PlanPoint
        σ_A (°, averaged over the azimuth), σ_φ (°) and σ_Ω (°/h).
    """
    cov = fit_covariance(noise, rate_hz, dwell_s, order)
    var_a, var_c, cov_ac = float(cov[0, 0]), float(cov[1, 1]), float(cov[0, 1])
    phi = math.radians(latitude_deg)
    sin, cos = math.sin(phi), math.cos(phi)
    amplitude = earth_rate_deg_h * cos
    heading = math.sqrt(max((var_a + var_c) / 2.0, 0.0)) / amplitude if amplitude > 0 else math.inf
    latitude = sin * sin * var_a + cos * cos * var_c - 2.0 * sin * cos * cov_ac
    rate = cos * cos * var_a + sin * sin * var_c + 2.0 * sin * cos * cov_ac
    return PlanPoint(
        order,
        float(dwell_s),
        float(dwell_s) * len(ORDERS[order]),
        math.degrees(heading),
        math.degrees(math.sqrt(max(latitude, 0.0)) / earth_rate_deg_h),
        math.sqrt(max(rate, 0.0)),
    )


@dataclass(frozen=True)
class AccuracyPlan:
    """Every order at every dwell, and for each order the dwell with the smallest heading σ."""

    points: tuple[PlanPoint, ...]
    best: dict[str, PlanPoint]
    near_best: dict[str, PlanPoint]  # the shortest dwell within 10 % of the best σ

    def at(self, order: str, dwell_s: float) -> PlanPoint:
        """The plan of ``order`` whose dwell is nearest ``dwell_s`` (in log terms)."""
        candidates = [p for p in self.points if p.order == order]
        return min(candidates, key=lambda p: abs(math.log(p.dwell_s / dwell_s)))

    def to_json(self) -> dict:
        return {
            "points": [p.to_json() for p in self.points],
            "best": {order: point.to_json() for order, point in self.best.items()},
            "near_best": {order: point.to_json() for order, point in self.near_best.items()},
        }


def accuracy_plan(
    noise: GyroNoise,
    rate_hz: float,
    latitude_deg: float,
    earth_rate_deg_h: float,
    dwells_s: tuple[float, ...] = PLAN_DWELLS_S,
) -> AccuracyPlan:
    """Plans for every order in :data:`ORDERS` at every dwell in ``dwells_s``.

    Parameters
    ----------
    noise : GyroNoise
        The station's gyro (its preset, or the Allan characterisation uploaded for it).
    rate_hz : float
        Sample rate (Hz).
    latitude_deg, earth_rate_deg_h : float
        The station's φ (°) and Ω (°/h).
    dwells_s : tuple of float
        The dwells per position to plan (s).

    Returns
    -------
    AccuracyPlan
        The points; each order's best dwell (the smallest heading σ) and the shortest dwell
        within 10 % of that σ (the same rule as :func:`app.core.dwell_advice.recommended_dwell`).
    """
    points = tuple(
        plan_point(noise, rate_hz, dwell, order, latitude_deg, earth_rate_deg_h)
        for order in ORDERS
        for dwell in dwells_s
    )
    best = {
        order: min((p for p in points if p.order == order), key=lambda p: p.heading_sigma_deg)
        for order in ORDERS
    }
    near_best = {
        order: next(
            p
            for p in points
            if p.order == order and p.heading_sigma_deg <= NEAR_BEST * best[order].heading_sigma_deg
        )
        for order in ORDERS
    }
    return AccuracyPlan(points, best, near_best)


# --- the class's scatter against the plan -------------------------------------------------


@dataclass(frozen=True)
class Agreement:
    """How a class's errors compare with the σ the plan predicted for each group.

    With z_i = e_i/σ_i (each group's error over its predicted 1σ) and k groups, χ² = Σz_i²
    follows χ²_k when the gyro's noise is the whole story, so the class's ratio
    R = √(χ²/k) (its RMS error in units of the predicted σ) lies in
    [√(χ²_k(2.5 %)/k), √(χ²_k(97.5 %)/k)] with 95 % probability."""

    groups: int
    ratio: float  # R, the RMS of z
    low: float
    high: float

    @property
    def verdict(self) -> str:
        """ "agrees", "larger" (more scatter than the noise explains) or "smaller" (less
        than the noise allows), or "too_few" below three groups."""
        if self.groups < MIN_GROUPS:
            return "too_few"
        if self.ratio > self.high:
            return "larger"
        if self.ratio < self.low:
            return "smaller"
        return "agrees"

    def to_json(self) -> dict:
        return {
            "groups": self.groups,
            "ratio": self.ratio,
            "low": self.low,
            "high": self.high,
            "verdict": self.verdict,
        }


MIN_GROUPS = 3


def scatter_agreement(errors: np.ndarray, sigmas: np.ndarray) -> Agreement:
    """Compare each group's error with its predicted 1σ (see :class:`Agreement`).

    Parameters
    ----------
    errors : numpy.ndarray
        Each group's error against its truth (heading °, latitude °, or Earth rate °/h).
    sigmas : numpy.ndarray
        The plan's 1σ for that group's dwell and order, same unit.

    Returns
    -------
    Agreement
        k, R = √(Σ(e_i/σ_i)²/k) and its 95 % range under the noise model.

    References
    ----------
    The χ² distribution of a sum of k squared standard normal variables.
    """
    from scipy.stats import chi2  # imported when first needed

    errors = np.asarray(errors, dtype=float)
    sigmas = np.asarray(sigmas, dtype=float)
    keep = np.isfinite(errors) & np.isfinite(sigmas) & (sigmas > 0)
    z = errors[keep] / sigmas[keep]
    k = int(z.size)
    if k == 0:
        return Agreement(0, math.nan, math.nan, math.nan)
    ratio = math.sqrt(float(np.mean(z * z)))
    low = math.sqrt(float(chi2.ppf(0.025, k)) / k)
    high = math.sqrt(float(chi2.ppf(0.975, k)) / k)
    return Agreement(k, ratio, low, high)
