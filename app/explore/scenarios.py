"""The error-analysis explorer: heading error against true azimuth, first order and Monte Carlo,
and the expected heading σ against dwell time.  Everything comes from ``app.core``.

Dwell view (lab-reference §3, §6): the heading σ of four back-to-back positions of T seconds
from the very noise model the simulator generates (:mod:`app.core.noise_model`: angle
random walk, Gauss–Markov bias instability, rate random walk, quantisation).  With Σ the
covariance of the four position means, x = (m1 − m3)/2 and y = (m2 − m4)/2 have variances
v_x, v_y, and averaged over the azimuth σ_A = √((v_x + v_y)/2)/H rad, H = Ω cos φ (for
white noise alone σ_m/(√2·H)).  A Gauss–Markov bias averages down again past its
correlation time -- there is no flat floor unless rate random walk makes the curve rise.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from app.core.allan_summary import dwell_lines
from app.core.dwell_advice import recommended_dwell
from app.core.error_analysis import ErrorSources, first_order
from app.core.error_monte_carlo import monte_carlo_heading_errors
from app.core.noise_model import GyroNoise
from app.core.presets import PRESETS
from app.core.sinusoid import fit_sinusoid
from app.core.units import EARTH_RATE_DEG_H

CURVE_STEP_DEG = 2.0
MC_STEP_DEG = 15.0
MAX_RUNS = 40
MAX_DWELL_S = 600.0


@dataclass
class ExplorerInput:
    method: str = "both"  # two | four | both (two and four) | seeker (the tilt paper's)
    latitude_deg: float = 60.0
    preset: str = "navigation-fog"
    noise: bool = True  # simulate the preset's random noise in the Monte Carlo
    dwell_s: float = 30.0
    runs: int = 8
    drift_deg_h: float = 0.0
    scale_factor_ppm: float = 0.0
    latitude_error_deg: float = 0.0
    indexing_arcsec: float = 0.0
    indexing_stop: int = 2
    pitch_deg: float = 0.0
    roll_deg: float = 0.0
    east_tilt_deg: float = 0.0
    level_deg: float = 0.0

    def sources(self) -> ErrorSources:
        return ErrorSources(
            drift_deg_h=self.drift_deg_h,
            scale_factor_ppm=self.scale_factor_ppm,
            latitude_error_deg=self.latitude_error_deg,
            indexing_deg=self.indexing_arcsec / 3600,
            indexing_stop=self.indexing_stop,
            level_deg=self.level_deg,
            east_tilt_deg=self.east_tilt_deg,
            pitch_deg=self.pitch_deg,
            roll_deg=self.roll_deg,
        )


@dataclass
class Curve:
    method: str
    azimuths_deg: list[float]
    formula_deg: list[float | None]
    mc_azimuths_deg: list[float] = field(default_factory=list)
    mc_mean_deg: list[float | None] = field(default_factory=list)
    mc_std_deg: list[float | None] = field(default_factory=list)


def _clean(values) -> list[float | None]:
    return [None if not math.isfinite(v) or abs(v) > 180 else float(v) for v in values]


def heading_error_curves(
    params: ExplorerInput, seed: int = 1, *, formula_at_mc_points: bool = False
) -> tuple[list[Curve], dict]:
    """Formula curves on a fine azimuth grid and Monte Carlo points on a coarse one
    (``formula_at_mc_points``: the formula on the coarse grid too, for tables)."""
    started = time.perf_counter()
    preset = PRESETS[params.preset]
    gyro = preset.ideal()
    if params.noise:
        gyro = replace(
            gyro,
            arw_deg_rt_h=preset.arw_deg_rt_h,
            bias_instability_deg_h=preset.bias_instability_deg_h,
            flicker_band_s=preset.flicker_band_s,
        )
    sources = params.sources()
    coarse = np.arange(MC_STEP_DEG / 2, 360.0, MC_STEP_DEG)
    fine = coarse if formula_at_mc_points else np.arange(0.0, 360.0 + 1e-9, CURVE_STEP_DEG)
    methods = ["two", "four"] if params.method == "both" else [params.method]
    runs = max(1, min(params.runs, MAX_RUNS)) if params.noise else 1
    curves = []
    for method in methods:
        formula = first_order(
            method, sources, fine, params.latitude_deg, stop_spacing_s=params.dwell_s
        )
        mc = monte_carlo_heading_errors(
            method,
            gyro,
            sources,
            coarse,
            latitude_deg=params.latitude_deg,
            runs=runs,
            dwell_s=params.dwell_s,
            seed=seed,
        )
        curves.append(
            Curve(
                method,
                fine.tolist(),
                _clean(formula),
                coarse.tolist(),
                _clean(mc.mean_error_deg),
                _clean(mc.std_error_deg),
            )
        )
    info = {
        "runs": runs,
        "points": int(coarse.size),
        "simulated_runs": runs * int(coarse.size) * len(methods),
        "seconds": round(time.perf_counter() - started, 3),
    }
    return curves, info


def dwell_curve(preset_name: str, latitude_deg: float, _=None) -> dict:
    """Expected four-position heading σ (°) against dwell per position, from the preset's
    noise model (flicker bias instability included); the white-noise part alone; the dwell
    that minimises σ within the lab's range -- the same rule and grid as the Allan page and
    ``gyrolab allan`` (:func:`app.core.dwell_advice.recommended_dwell`) -- with the advice in
    words when a translator ``_`` is given."""
    preset = PRESETS[preset_name]
    amplitude = EARTH_RATE_DEG_H * math.cos(math.radians(latitude_deg))
    advice = recommended_dwell(GyroNoise.from_preset(preset), preset.sample_rate_hz)
    scale = 1.0 / amplitude if amplitude > 0 else math.nan
    sigma, white = advice.sigma * scale, advice.white_sigma * scale
    return {
        "dwell_s": advice.dwell_s.tolist(),
        "sigma_deg": sigma.tolist(),
        "white_only_deg": white.tolist(),
        "floor_deg": float(np.min(sigma)),
        "best_dwell_s": advice.recommended_s,
        "lower_bound": advice.lower_bound,
        "near_best_s": advice.near_best_s,
        "knee_s": advice.near_best_s,
        "advice": dwell_lines(advice.to_json(), _) if _ is not None else [],
        "arw_deg_rt_h": preset.arw_deg_rt_h,
        "bias_instability_deg_h": preset.bias_instability_deg_h,
    }


ORDERS: dict[str, tuple[float, ...]] = {  # dial angles (ccw turns) in recording order
    "1234": (0.0, -90.0, -180.0, -270.0),
    "1324": (0.0, -180.0, -90.0, -270.0),
    "12344321": (0.0, -90.0, -180.0, -270.0, -270.0, -180.0, -90.0, 0.0),
}


def drift_order_curves(latitude_deg: float, dwell_s: float, bias_drift_deg_h_per_h: float) -> dict:
    """Heading error (°) against the true azimuth that a linear bias drift ḃ causes for
    each recording order, positions back to back (lab-reference §3): each position's mean
    is H·cos A_i + ḃ·t̄_i, solved as the lab does, without a drift term."""
    amplitude = EARTH_RATE_DEG_H * math.cos(math.radians(latitude_deg))
    azimuths = np.arange(0.0, 360.0, 5.0)
    out: dict = {"azimuth_deg": azimuths.tolist(), "orders": {}}
    for name, angles in ORDERS.items():
        mean_times_h = (np.arange(len(angles)) + 0.5) * dwell_s / 3600.0
        errors = []
        for azimuth in azimuths:
            means = amplitude * np.cos(np.radians(azimuth + np.asarray(angles)))
            means = means + bias_drift_deg_h_per_h * mean_times_h
            fit = fit_sinusoid([[m, m] for m in means], angles)
            found = math.degrees(math.atan2(-fit.c, fit.a)) + angles[0]
            errors.append((found - azimuth + 180.0) % 360.0 - 180.0)
        out["orders"][name] = errors
    return out


# Presets reproducing the papers' figures and the contrasts (lab-reference §4).  The tilt
# paper's presets use its own instrument, the two-axis seeker; "-single-axis" is the
# handout's FOG under the same tilt, solved with arccos, as a labelled contrast.
PAPER_TILTS = {"level": (0.0, 0.0), "5": (5.0, -5.0), "10": (-10.0, 10.0), "20": (20.0, 20.0)}

SCENARIOS: dict[str, dict] = {
    **{
        f"indexing-{'level' if key == 'level' else 'tilt-' + key}": {
            "method": "seeker",
            "latitude_deg": 60.0,
            "indexing_arcsec": 900.0,
            "pitch_deg": pitch,
            "roll_deg": roll,
            "noise": False,
        }
        for key, (pitch, roll) in PAPER_TILTS.items()
    },
    "indexing-tilt-5-single-axis": {
        "method": "two",
        "latitude_deg": 60.0,
        "indexing_arcsec": 900.0,
        "pitch_deg": 5.0,
        "roll_deg": -5.0,
        "noise": False,
    },
    "drift": {"method": "two", "latitude_deg": 40.0, "drift_deg_h": 0.05, "noise": False},
    "scale-factor": {
        "method": "two",
        "latitude_deg": 40.0,
        "scale_factor_ppm": 2000.0,
        "noise": False,
    },
    "latitude-error": {
        "method": "two",
        "latitude_deg": 40.0,
        "latitude_error_deg": 0.1,
        "noise": False,
    },
    "four-cancels": {
        "method": "both",
        "latitude_deg": 40.0,
        "scale_factor_ppm": 2000.0,
        "latitude_error_deg": 0.1,
        "noise": False,
    },
    "four-east-tilt": {
        "method": "both",
        "latitude_deg": 40.0,
        "east_tilt_deg": 1.0,
        "noise": False,
    },
    "noise": {
        "method": "both",
        "latitude_deg": 40.0,
        "preset": "tactical-fog",
        "noise": True,
        "runs": 10,
        "dwell_s": 60.0,
    },
}


def scenario_input(name: str) -> ExplorerInput:
    return ExplorerInput(**SCENARIOS[name])
