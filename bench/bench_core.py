"""Time the science core on 1e6 samples: solve (per position), simulate, Allan deviation.

    .venv/bin/python bench/bench_core.py

Prints the best of several repeats for each; copy the figures into README.md.
"""

from __future__ import annotations

import platform
import time

import numpy as np

from app.core.allan import allan_deviation
from app.core.gyro_stream import GyroStream
from app.core.presets import PRESETS
from app.core.simulate import Setup, simulate_static
from app.core.sinusoid import heading_angles
from app.core.solve import solve_heading

N = 1_000_000


def best_of(function, repeats: int = 5) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return min(times)


def main() -> None:
    rng = np.random.default_rng(0)
    positions = [rng.normal(10 * np.cos(np.radians(a)), 0.1, N) for a in (0, -90, -180, -270)]
    angles = heading_angles(4)
    preset = PRESETS["tactical-fog"]
    record = simulate_static(preset, Setup(40.0), N / preset.sample_rate_hz)
    rates = np.full(N, 5.0)
    figures = {
        "solve heading, 4 positions × 1e6 samples": best_of(
            lambda: solve_heading(positions, angles)
        ),
        "simulate 1e6 samples (all error terms)": best_of(
            lambda: GyroStream(preset, 1).read(rates, 0.3)
        ),
        "Allan deviation of 1e6 samples (+ read-outs)": best_of(
            lambda: allan_deviation(record, preset.sample_rate_hz), 3
        ),
    }
    print(
        f"machine: {platform.machine()}, {platform.processor() or 'cpu'}, "
        f"Python {platform.python_version()}, numpy {np.__version__}"
    )
    for name, seconds in figures.items():
        print(f"{name:48s} {seconds * 1000:8.1f} ms")


if __name__ == "__main__":
    main()
