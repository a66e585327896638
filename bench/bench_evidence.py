"""False alarms and detections of the data evidence (app/core/data_evidence.py).

Honest classes of 60 from the simulated gyro -- every preset, every recording method
(the simulator's samples with their times, a CSV export of them at 6 decimals with times
at 3, 12 readings a position typed at 2 decimals), warm or started cold -- and planted
cases in the same classes: numbers invented around the right means, another group's take
copied with an offset, readings smoothed with a 5-point running average, and the
handout's own tables retyped.  A part (four positions) counts as flagged when any check
fires on it.

    .venv/bin/python bench/bench_evidence.py [--students 60] [--presets teaching-fog ...]
"""

from __future__ import annotations

import argparse
import csv
import math
import time
from pathlib import Path

import numpy as np

from app.core.data_evidence import class_copies, off_grid, part_evidence
from app.core.noise_model import GyroNoise
from app.core.output_grid import GridPart, class_step
from app.core.presets import PRESETS
from app.core.simulate import Setup, simulate_run
from app.core.sinusoid import elevation_angles, heading_angles

LATITUDE = 39.93
DWELL_S = {"teaching-fog": 120.0}  # 12 readings at 0.1 Hz; the others 60 s
TYPED_READINGS = 12
METHODS = ("simulator", "csv", "typed")
PLANTS = ("invented", "copied", "smoothed", "handout")
HANDOUT = Path(__file__).resolve().parent.parent / "app" / "core" / "data"


TIMES: dict[tuple[str, int, str, bool], dict] = {}  # the honest parts' reading times


def honest_parts(preset_name: str, student: int, method: str, cold: bool) -> dict:
    """One student's two parts as the method records them: part → list of 4 arrays (the
    simulator's and the CSV's reading times, CSV at 3 decimals, kept in ``TIMES``)."""
    preset = PRESETS[preset_name]
    dwell = DWELL_S.get(preset_name, 60.0)
    rng = np.random.default_rng(student)
    setup = Setup(LATITUDE, float(rng.uniform(0, 360)))
    start = 0.0 if cold else 3600.0
    parts = {}
    for part, angles in (("heading", heading_angles(4)), ("latitude", elevation_angles(4))):
        run = simulate_run(
            preset, setup, part, angles, dwell, seed=student * 7 + len(part), start_s=start
        )
        if method == "simulator":
            parts[part] = run.positions
            TIMES.setdefault((preset_name, student, method, cold), {})[part] = run.times_s
        elif method == "csv":
            parts[part] = [np.round(v, 6) for v in run.positions]
            TIMES.setdefault((preset_name, student, method, cold), {})[part] = [
                np.round(t, 3) for t in run.times_s
            ]
        else:  # typed as people round: most to 2 decimals, some to 1, a few to 3
            decimals = int(rng.choice([2, 1, 3], p=[0.7, 0.2, 0.1]))
            parts[part] = [np.round(v[:TYPED_READINGS], decimals) for v in run.positions]
    return parts


def invented(parts: dict, rng: np.random.Generator) -> dict:
    """Numbers made up around each position's mean: a narrow human jitter, 2 decimals,
    last digits leaning to 0 and 5."""
    out = {}
    for part, positions in parts.items():
        made = []
        for v in positions:
            spread = max(float(np.std(v)), 0.01)
            values = np.mean(v) + rng.uniform(-spread, spread, TYPED_READINGS)
            hundredths = np.round(values * 100)
            lean = rng.random(TYPED_READINGS) < 0.5
            hundredths[lean] = np.round(hundredths[lean] / 5) * 5
            made.append(hundredths / 100)
        out[part] = made
    return out


def smoothed(parts: dict) -> dict:
    kernel = np.ones(5) / 5
    return {
        part: [np.convolve(v, kernel, mode="valid") if v.size >= 9 else v for v in positions]
        for part, positions in parts.items()
    }


def handout_parts() -> dict:
    out = {}
    for part, name in (("heading", "handout_horizontal.csv"), ("latitude", "handout_vertical.csv")):
        with (HANDOUT / name).open(encoding="utf-8") as handle:
            rows = list(csv.DictReader(handle))
        out[part] = [np.array([float(r[f"position_{k}"]) for r in rows]) for k in range(1, 5)]
    return out


PLANTED = 20  # of each case, per class


def evaluate(preset_name: str, method: str, cold: bool, students: int, grid: bool) -> dict:
    """Flag rates of honest parts and detection rates of each planted case, one class."""
    preset = PRESETS[preset_name]
    noise, rate = GyroNoise.from_preset(preset), preset.sample_rate_hz
    typed = method == "typed"
    rng = np.random.default_rng(99)
    honest = {f"s{i}": honest_parts(preset_name, i, method, cold) for i in range(students)}
    planted = {}
    for i, plant in enumerate(PLANTS):  # a few of each, among the honest class
        for k in range(PLANTED):
            source = honest[f"s{(7 * i + k) % students}"]
            if plant == "invented":
                planted[f"{plant}{k}"] = invented(source, rng)
            elif plant == "copied":
                planted[f"{plant}{k}"] = {
                    part: [v + 0.03 for v in positions] for part, positions in source.items()
                }
            elif plant == "smoothed":
                planted[f"{plant}{k}"] = smoothed(source)
            else:
                planted[f"{plant}{k}"] = handout_parts()
    groups = {**honest, **planted}
    takes = [
        (group, part, positions)
        for group, parts in groups.items()
        for part, positions in parts.items()
    ]
    copies = class_copies(takes)
    flagged: dict[str, set[str]] = {}
    if not grid:  # a real gyro's output step, as the class's own readings show it
        whole = {
            g: {p: GridPart.of(np.concatenate(v)) for p, v in parts.items()}
            for g, parts in groups.items()
        }
        class_parts = [v for g in honest for v in whole[g].values()]
        model_step = 3600.0 * noise.angle_lsb_deg * rate  # the characterisation's quantisation
        honest_step = class_step(class_parts, model_step)
        for group, parts in groups.items():
            # each planted group is one case in a class of honest students
            step = (
                honest_step
                if group in honest
                else class_step(class_parts + list(whole[group].values()), model_step)
            )
            for part, positions in parts.items():
                if step and off_grid(part, positions, step):
                    flagged.setdefault(group, set()).add("off_class_grid")
    for group, parts in groups.items():
        plant_typed = typed or group.startswith(("invented", "handout"))
        timed = (
            TIMES.get((preset_name, int(group[1:]), method, cold), {}) if group in honest else {}
        )
        for part, positions in parts.items():
            found = part_evidence(
                part, positions, plant_typed, noise, rate, simulated=grid, times=timed.get(part)
            )
            found += [e for e in copies.get(group, []) if e.part == part]
            if found:
                flagged.setdefault(group, set()).update(e.check for e in found)
    # a copied take's source is flagged too (it matches the copy): that is not a false alarm
    sources = {f"s{(7 * PLANTS.index('copied') + k) % students}" for k in range(PLANTED)}
    honest_flagged = [
        g for g in honest if g in flagged and not (g in sources and flagged[g] == {"copy"})
    ]
    row = {
        "preset": preset_name,
        "method": method,
        "start": "cold" if cold else "warm",
        "honest": len(honest_flagged) / students,
        "honest_checks": sorted({c for g in honest_flagged for c in flagged[g]}),
    }
    for plant in PLANTS:
        hits = [g for g in planted if g.startswith(plant) and g in flagged]
        row[plant] = len(hits) / PLANTED
        row[f"{plant}_by"] = sorted({c for g in hits for c in flagged[g]})
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--students", type=int, default=60)
    parser.add_argument("--presets", nargs="*", default=sorted(PRESETS))
    parser.add_argument(
        "--no-grid",
        action="store_true",
        help="leave out the output-grid check (as for a real gyro the teacher characterised)",
    )
    args = parser.parse_args()
    started = time.perf_counter()
    print(
        "| preset | method | start | honest students flagged | by | "
        + " | ".join(f"{p} found (by)" for p in PLANTS)
        + " |"
    )
    print("|---|---|---|---|---|" + "---|" * len(PLANTS))
    for name in args.presets:
        for method in METHODS:
            for cold in (False, True):
                r = evaluate(name, method, cold, args.students, not args.no_grid)
                found = [f"{100 * r[p]:.0f} % ({', '.join(r[p + '_by']) or '—'})" for p in PLANTS]
                print(
                    f"| {r['preset']} | {r['method']} | {r['start']} | {100 * r['honest']:.1f} % "
                    f"| {', '.join(r['honest_checks']) or '—'} | " + " | ".join(found) + " |",
                    flush=True,
                )
    print(f"\n{math.ceil(time.perf_counter() - started)} s")


if __name__ == "__main__":
    main()
