"""How often the reported 1σ of the heading covers the true error, per simulator preset and
dwell: the white-noise σ (s/√n with Student-t) against the σ from the preset's noise model
(app.core.noise_model).  An honest 1σ covers 68 %.

    .venv/bin/python bench/bench_coverage.py [--runs 1000] [--dwells 10 60 300 1800]
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass

import numpy as np

from app.core.exceptions import UserError
from app.core.noise_model import GyroNoise, back_to_back
from app.core.presets import PRESETS
from app.core.simulate import Setup, simulate_run
from app.core.sinusoid import heading_angles
from app.core.solve import solve_heading

LATITUDE = 39.93


@dataclass
class Coverage:
    preset: str
    dwell_s: float
    runs: int
    solved: int
    white: float
    model: float

    def row(self) -> str:
        return (
            f"| {self.preset} | {self.dwell_s:g} s | {self.solved}/{self.runs} | "
            f"{100 * self.white:.1f} % | {100 * self.model:.1f} % |"
        )


def coverage(preset_name: str, dwell_s: float, runs: int, seed: int = 2026) -> Coverage:
    """Seeded Monte Carlo: random true azimuths, four positions counter-clockwise, recorded
    after the gyro has warmed up (five warm-up time constants after switch-on)."""
    preset = PRESETS[preset_name]
    warmed_up = 5.0 * preset.warmup_time_constant_s
    noise = GyroNoise.from_preset(preset)
    angles = heading_angles(4, "ccw")
    rng = np.random.default_rng(seed)
    azimuths = rng.uniform(0.0, 360.0, runs)
    white_hits = model_hits = solved = 0
    for run, azimuth in enumerate(azimuths):
        simulated = simulate_run(
            preset,
            Setup(LATITUDE, float(azimuth)),
            "heading",
            angles,
            dwell_s,
            seed=seed + run,
            start_s=warmed_up,
        )
        counts = [p.size for p in simulated.positions]
        cov = noise.mean_covariance(back_to_back(counts, preset.sample_rate_hz, start_s=warmed_up))
        try:
            white = solve_heading(simulated.positions, angles, true_azimuth_deg=float(azimuth))
            model = solve_heading(
                simulated.positions,
                angles,
                true_azimuth_deg=float(azimuth),
                position_cov=cov,
                indexing_sigma_deg=noise.indexing_sigma_deg,
            )
        except UserError:
            continue  # not significant: refused, never printed
        solved += 1
        white_hits += abs(white.azimuth_error_deg) <= white.azimuth_sigma_deg
        model_hits += abs(model.azimuth_error_deg) <= model.azimuth_sigma_deg
    solved_runs = max(solved, 1)
    return Coverage(
        preset_name, dwell_s, runs, solved, white_hits / solved_runs, model_hits / solved_runs
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=1000)
    parser.add_argument("--dwells", type=float, nargs="+", default=[10, 60, 300, 1800])
    parser.add_argument("--presets", nargs="+", default=sorted(PRESETS))
    args = parser.parse_args()
    print(f"heading 1σ coverage, {args.runs} seeded runs each, φ = {LATITUDE}°")
    print("| preset | dwell per position | solved | white-noise σ | noise-model σ |")
    print("|---|---|---|---|---|")
    for name in args.presets:
        for dwell in args.dwells:
            start = time.perf_counter()
            result = coverage(name, dwell, args.runs)
            print(result.row(), f"<!-- {time.perf_counter() - start:.1f} s -->", flush=True)


if __name__ == "__main__":
    main()
