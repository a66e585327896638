"""Allan fit against noise that GyroLab did not generate: how often each IEEE 952 term is
resolved where it is present and left unresolved where it is absent, how close the
resolved values are, and how often their 68 % intervals hold the truth.

Records come from tests/noise_sources.py (Kasdin–Walter flicker, white, random walk,
angle quantisation -- written independently of app/core/simulate.py; a sinusoid added for
the air-conditioning swing) and, for the presets,
from GyroLab's own simulator (flicker as a sum of Gauss–Markov processes).

    .venv/bin/python bench/bench_allan_fit.py [--records 100]
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from app.core.allan import allan_deviation
from app.core.gyro_stream import GyroStream
from app.core.presets import PRESETS

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # the tests' generator
from tests.noise_sources import static_record  # noqa: E402

TERMS = {"arw": "arw", "bias_instability": "flicker", "rrw": "rrw", "sinusoid": "swing"}
CASES = {  # name: (hours, rate Hz, terms of tests/noise_sources.static_record)
    "white": (2.0, 10.0, {"arw": 0.012}),
    "flicker": (2.0, 10.0, {"flicker": 0.05}),
    "rrw": (2.0, 10.0, {"rrw": 0.1}),
    "mixed": (24.0, 1.0, {"arw": 0.002, "flicker": 0.05, "rrw": 0.1}),
    "mixed, quantised": (24.0, 1.0, {"arw": 0.002, "flicker": 0.05, "rrw": 0.1, "lsb_deg": 2e-5}),
    "MEMS-like, 100 Hz": (2.8, 100.0, {"arw": 0.3, "flicker": 40.0, "rrw": 2.0}),
    # a bias swinging with the lab's air conditioning: 0.05 °/h every 20 minutes
    "flicker + 20-min swing": (8.0, 5.0, {"arw": 0.005, "flicker": 0.02, "swing": 0.05}),
}
SWING_PERIOD_S = 1200.0


def independent_record(hours: float, rate: float, seed: int, terms: dict) -> np.ndarray:
    """tests/noise_sources.static_record, plus a sinusoid of random phase for "swing"."""
    noise = {k: v for k, v in terms.items() if k != "swing"}
    values = static_record(hours, rate, seed=seed, **noise)
    if terms.get("swing"):
        phase = np.random.default_rng(seed).uniform(0.0, 2.0 * np.pi)
        t = np.arange(values.size) / rate
        values = values + terms["swing"] * np.sin(2.0 * np.pi * t / SWING_PERIOD_S + phase)
    return values


def preset_record(name: str, hours: float, seed: int) -> tuple[np.ndarray, float, dict]:
    gyro = replace(PRESETS[name], turn_on_bias_sigma_deg_h=0.0).without("warmup")
    count = int(hours * 3600 * gyro.sample_rate_hz)
    truth = {"arw": gyro.arw_deg_rt_h, "flicker": gyro.bias_instability_deg_h,
             "rrw": gyro.rrw_deg_h_rt_h}  # fmt: skip
    return GyroStream(gyro, seed).read(np.full(count, 10.0)), gyro.sample_rate_hz, truth


def table(name: str, records, row_seconds: float) -> list[str]:
    counts = {t: 0 for t in TERMS}
    ratios = {t: [] for t in TERMS}
    covered = {t: 0 for t in TERMS}
    with_interval = {t: 0 for t in TERMS}
    truth = {}
    for values, rate, truth in records:
        result = allan_deviation(values, rate)
        for term, key in TERMS.items():
            estimate = result.terms[term]
            if not estimate.resolved:
                continue
            counts[term] += 1
            true = truth.get(key, 0.0)
            if true:
                ratios[term].append(estimate.value / true)
                if estimate.interval:
                    with_interval[term] += 1
                    covered[term] += estimate.interval[0] <= true <= estimate.interval[1]
    rows = []
    total = len(records)
    cells = []
    for term, key in TERMS.items():
        true = truth.get(key, 0.0)
        if true:
            mean = (
                f"{np.mean(ratios[term]):.3f} ± {np.std(ratios[term]):.3f}" if ratios[term] else "—"
            )
            cover = (
                f"{100 * covered[term] / with_interval[term]:.0f} %" if with_interval[term] else "—"
            )
            cells.append(f"{true:g}: {counts[term]}/{total} resolved, {mean}, {cover}")
        else:
            cells.append(f"absent: {counts[term]}/{total} resolved")
    rows.append(f"| {name} | " + " | ".join(cells) + f" | <!-- {row_seconds:.0f} s -->")
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=100)
    args = parser.parse_args()
    print(f"{args.records} records per row; each cell: truth: resolved, estimate/truth "
          "(mean ± spread), share of 68 % intervals holding the truth")  # fmt: skip
    print("| records | N (°/√h) | B (°/h) | K (°/h/√h) | swing Ω0 (°/h) |")
    print("|---|---|---|---|---|")
    for name, (hours, rate, terms) in CASES.items():
        began = time.perf_counter()
        records = []
        for seed in range(args.records):
            values = independent_record(hours, rate, 1000 + seed, terms)
            records.append((values, rate, terms))
        label = f"{name} ({hours:g} h at {rate:g} Hz, independent generator)"
        for line in table(label, records, time.perf_counter() - began):
            print(line, flush=True)
    for preset in sorted(PRESETS):
        began = time.perf_counter()
        records = [preset_record(preset, 24.0, 500 + seed) for seed in range(args.records)]
        label = f"preset {preset} (24 h, GyroLab's simulator)"
        for line in table(label, records, time.perf_counter() - began):
            print(line, flush=True)


if __name__ == "__main__":
    main()
