"""How well the joint Allan fit recovers each preset's N and B from one 6 h static record,
and whether its bootstrap intervals cover the truth as often as they say (68.3 %).

    .venv/bin/python bench/bench_allan_fit.py [--records 40] [--replicates 40] [--hours 6]
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace

import numpy as np

from app.core.allan import allan_deviation
from app.core.allan_intervals import fit_intervals
from app.core.presets import PRESETS
from app.core.simulate import GyroStream


def recovery(name: str, records: int, replicates: int, hours: float) -> str:
    # a characterisation record is taken after warm-up: the warm-up transient is not noise
    preset = replace(PRESETS[name], turn_on_bias_sigma_deg_h=0.0).without("warmup")
    count = int(hours * 3600 * preset.sample_rate_hz)
    ratio_n, ratio_b, cover_n, cover_b = [], [], 0, 0
    for seed in range(records):
        record = GyroStream(preset, 10_000 + seed).read(np.full(count, 10.0))
        result = allan_deviation(record, preset.sample_rate_hz)
        ranges = fit_intervals(
            result, preset.sample_rate_hz, count, replicates=replicates, seed=seed
        )
        ratio_n.append(result.arw_deg_rt_h / preset.arw_deg_rt_h)
        ratio_b.append((result.bias_instability_deg_h or 0.0) / preset.bias_instability_deg_h)
        low, high = ranges.arw_deg_rt_h
        cover_n += low <= preset.arw_deg_rt_h <= high
        if ranges.bias_instability_deg_h is not None:
            low, high = ranges.bias_instability_deg_h
            cover_b += low <= preset.bias_instability_deg_h <= high
    return (
        f"| {name} | {preset.arw_deg_rt_h:g} | {np.mean(ratio_n):.3f} ± {np.std(ratio_n):.3f} | "
        f"{100 * cover_n / records:.0f} % | {preset.bias_instability_deg_h:g} | "
        f"{np.mean(ratio_b):.3f} ± {np.std(ratio_b):.3f} | {100 * cover_b / records:.0f} % |"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=40)
    parser.add_argument("--replicates", type=int, default=40)
    parser.add_argument("--hours", type=float, default=6.0)
    args = parser.parse_args()
    started = time.perf_counter()
    print(f"{args.records} records of {args.hours:g} h per preset, {args.replicates} bootstrap "
          "replicates each; estimate/truth as mean ± spread over the records")  # fmt: skip
    print("| preset | N (°/√h) | N̂/N | N interval covers | B (°/h) | B̂/B | B interval covers |")
    print("|---|---|---|---|---|---|---|")
    for name in sorted(PRESETS):
        print(recovery(name, args.records, args.replicates, args.hours), flush=True)
    print(f"({time.perf_counter() - started:.0f} s)")


if __name__ == "__main__":
    main()
