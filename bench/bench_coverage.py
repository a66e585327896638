"""How often the reported 1σ of the heading covers the true error, per simulator preset,
dwell, and warm or cold start -- through the same path as ``gyrolab solve --gyro-preset``
and the lab: the preset's noise model (flicker bias instability included) for the σ, the
recording times for the warm-up check, the station's H = Ω cos φ for the exact σ of the
angle.  An honest 1σ covers 68 % (warm); a cold start's error must lie within its 2σ (the
95 % interval) or the run be flagged as warming up, in ≥ 95 % of runs.

    .venv/bin/python bench/bench_coverage.py [--runs 1000] [--dwells 10 60 300 1800]
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import dataclass

import numpy as np

from app.core.exceptions import UserError
from app.core.noise_model import GyroNoise, Window
from app.core.presets import PRESETS
from app.core.simulate import Setup, simulate_run
from app.core.sinusoid import heading_angles
from app.core.solve import solve_heading
from app.core.units import EARTH_RATE_DEG_H

LATITUDE = 39.93
AMPLITUDE = EARTH_RATE_DEG_H * math.cos(math.radians(LATITUDE))  # H at the known station


@dataclass
class Coverage:
    preset: str
    dwell_s: float
    start: str
    runs: int
    solved: int
    white: float  # s/√n with Student-t, no noise model, no warm-up check
    model: float  # the noise model's σ (widened where a drift is flagged)
    flagged: float  # share of solved runs flagged as warming up
    covered_or_flagged: float  # |error| ≤ 2σ (the 95 % interval) or flagged

    def row(self) -> str:
        return (
            f"| {self.preset} | {self.dwell_s:g} s | {self.start} | {self.solved}/{self.runs} | "
            f"{100 * self.white:.1f} % | {100 * self.model:.1f} % | {100 * self.flagged:.1f} % | "
            f"{100 * self.covered_or_flagged:.1f} % |"
        )


def coverage(
    preset_name: str,
    dwell_s: float,
    runs: int,
    *,
    cold: bool,
    seed: int = 2026,
    warm_s: float = 3600.0,
) -> Coverage:
    """Seeded Monte Carlo: random true azimuths, four positions counter-clockwise, back to
    back, started at switch-on (cold) or after ``warm_s`` (warm: an hour by default,
    ``gyrolab simulate``'s; each run simulates the gyro's history since switch-on)."""
    preset = PRESETS[preset_name]
    start_s = 0.0 if cold else warm_s
    noise = GyroNoise.from_preset(preset)
    angles = heading_angles(4, "ccw")
    rng = np.random.default_rng(seed)
    azimuths = rng.uniform(0.0, 360.0, runs)
    white_hits = model_hits = flagged = either = solved = 0
    for run, azimuth in enumerate(azimuths):
        simulated = simulate_run(
            preset,
            Setup(LATITUDE, float(azimuth)),
            "heading",
            angles,
            dwell_s,
            seed=seed + run,
            start_s=start_s,
        )
        windows = [Window(float(t[0]), t.size / preset.sample_rate_hz) for t in simulated.times_s]
        try:
            white = solve_heading(simulated.positions, angles, true_azimuth_deg=float(azimuth))
            model = solve_heading(
                simulated.positions,
                angles,
                true_azimuth_deg=float(azimuth),
                position_cov=noise.mean_covariance(windows),
                warm_up_cov=noise.warm_up_cov(windows),
                indexing_sigma_deg=noise.indexing_sigma_deg,
                times_s=simulated.times_s,
                expected_amplitude_deg_h=AMPLITUDE,
            )
        except UserError:
            continue  # not significant: refused, never printed
        solved += 1
        white_hits += abs(white.azimuth_error_deg) <= white.azimuth_sigma_deg
        hit = abs(model.azimuth_error_deg) <= model.azimuth_sigma_deg
        model_hits += hit
        is_flagged = bool(model.drift_check and model.drift_check.flagged)
        flagged += is_flagged
        either += abs(model.azimuth_error_deg) <= 2 * model.azimuth_sigma_deg or is_flagged
    n = max(solved, 1)
    return Coverage(
        preset_name,
        dwell_s,
        "cold" if cold else "warm",
        runs,
        solved,
        white_hits / n,
        model_hits / n,
        flagged / n,
        either / n,
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=1000)
    parser.add_argument("--dwells", type=float, nargs="+", default=[10, 60, 300, 1800])
    parser.add_argument("--presets", nargs="+", default=sorted(PRESETS))
    parser.add_argument("--starts", nargs="+", default=["warm", "cold"])
    args = parser.parse_args()
    print(f"heading 1σ coverage, {args.runs} seeded runs each, φ = {LATITUDE}°")
    print(
        "| preset | dwell per position | start | solved | white-noise σ | noise-model σ "
        "| flagged warming up | within 2σ or flagged |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for name in args.presets:
        for dwell in args.dwells:
            for start in args.starts:
                began = time.perf_counter()
                result = coverage(name, dwell, args.runs, cold=start == "cold")
                print(result.row(), f"<!-- {time.perf_counter() - began:.1f} s -->", flush=True)


if __name__ == "__main__":
    main()
