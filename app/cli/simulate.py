"""``gyrolab simulate``: the simulated gyro's readings as long CSV -- four (or N) positions
for the heading or the latitude, or one static record -- and ``--list-presets``."""

from __future__ import annotations

import argparse
import sys
from dataclasses import asdict, replace

import numpy as np

from app.cli.science import CommandError, check_finite, to_json_text
from app.core.gyro_stream import GyroStream
from app.core.long_readings import readings_to_long_csv
from app.core.presets import PRESETS
from app.core.simulate import Setup, simulate_run, simulate_static
from app.core.sinusoid import elevation_angles, heading_angles
from app.core.units import EARTH_RATE_DEG_H

WARM_GYRO_S = 3600.0  # simulate's default: a lab gyro is usually left on
MAX_SAMPLES = 5_000_000  # a position's (or a static record's) readings
MAX_POSITIONS = 360  # one every degree
MAX_SETTLE_S = 3600.0  # discarded after each turn (the lab page's stream: 120 s)
MAX_INDEXING_ARCSEC = 3600.0  # a table read to a degree


def check_simulation_options(args: argparse.Namespace) -> None:
    """Every number the simulation takes, refused in words where it cannot be simulated
    (NaN settle and a negative seed were tracebacks; NaN Earth rate wrote NaN readings; a
    settle of 1e9 s or a 1e9 s static record ran out of memory; 0 or negative rates,
    settles, lengths and σ were taken)."""
    for name in (
        "latitude", "earth_rate", "azimuth", "pitch", "roll", "elevation", "rate",
        "seconds", "seconds_per_position", "settle", "indexing_sigma", "warm_up",
    ):  # fmt: skip
        check_finite(f"--{name.replace('_', '-')}", getattr(args, name))
    if not -90 <= args.latitude <= 90:
        raise CommandError("cli.latitude_range")
    if not 0 < args.earth_rate < 1000:
        raise CommandError("cli.earth_rate_range")
    for name in ("rate", "seconds", "seconds_per_position"):
        value = getattr(args, name)
        if value is not None and value <= 0:
            raise CommandError("cli.not_positive", name=f"--{name.replace('_', '-')}")
    ranges = (
        ("--settle", args.settle, 0.0, MAX_SETTLE_S),
        ("--positions", args.positions, 3, MAX_POSITIONS),
        ("--indexing-sigma", args.indexing_sigma, 0.0, MAX_INDEXING_ARCSEC),
        ("--pitch", args.pitch, -90.0, 90.0),
        ("--roll", args.roll, -90.0, 90.0),
        ("--elevation", args.elevation, -90.0, 90.0),
    )
    for name, value, low, high in ranges:
        if value is not None and not low <= value <= high:
            raise CommandError("cli.between", name=name, low=f"{low:g}", high=f"{high:g}")
    if args.seed < 0:
        raise CommandError("cli.seed_negative")
    if not 0 <= args.warm_up <= 86_400:
        raise CommandError("cli.warm_up_range")


def preset_table() -> list[dict]:
    """Every preset's parameters, units in the names, with its source and description."""
    rows = []
    for name in sorted(PRESETS):
        fields = asdict(PRESETS[name])
        fields["misalignment_deg"] = list(fields["misalignment_deg"])
        rows.append(fields)
    return rows


def _list_presets(as_json: bool) -> int:
    rows = preset_table()
    if as_json:
        print(to_json_text(rows))
        return 0
    for row in rows:
        print(row["name"])
        for key, value in row.items():
            if key not in ("name", "description", "source"):
                print(f"  {key} = {value}")
        print(f"  source: {row['source']}")
    return 0


def simulate_command(args: argparse.Namespace) -> int:
    if args.list_presets:
        return _list_presets(args.json)
    if args.part is None:
        raise CommandError("cli.name_what_to_simulate")
    if args.latitude is None:
        raise CommandError("cli.latitude_required")
    check_simulation_options(args)
    preset = PRESETS[args.preset]
    if args.rate:
        preset = replace(preset, sample_rate_hz=args.rate)
    if args.indexing_sigma is not None:
        preset = replace(preset, indexing_sigma_arcsec=args.indexing_sigma)
    setup = Setup(
        args.latitude,
        args.azimuth,
        args.earth_rate,
        args.pitch,
        args.roll,
        args.elevation if args.part == "heading" else 0.0,
    )
    if args.part == "static":
        seconds = args.seconds or args.seconds_per_position or 600.0
        if seconds * preset.sample_rate_hz > MAX_SAMPLES:
            raise CommandError("cli.record_length_range", most=f"{MAX_SAMPLES:,}")
        values = simulate_static(
            preset,
            setup,
            seconds,
            seed=args.seed,
            elevation_deg=args.elevation,
            start_s=args.warm_up,
        )
        skip = int(round(args.warm_up * preset.sample_rate_hz))
        times = [(skip + np.arange(values.size)) / preset.sample_rate_hz]
        clock = GyroStream(preset, args.seed)
        clock.samples_read = skip
        temperatures = [clock.temperatures_c(values.size)]
        sys.stdout.write(
            readings_to_long_csv(
                [values], [0.0], times, temperatures_c=temperatures if args.temperature else None
            )
        )
        return 0
    seconds = args.seconds_per_position or args.seconds or 10.0
    if seconds * preset.sample_rate_hz > MAX_SAMPLES:
        raise CommandError("cli.dwell_range")
    step = 360.0 / args.positions
    if args.part == "heading":
        dials = heading_angles(args.positions, args.rotation, 0.0, step)
    else:
        dials = elevation_angles(args.positions, 0.0, step)
    run = simulate_run(
        preset,
        setup,
        args.part,
        dials,
        seconds,
        settle_s=args.settle,
        seed=args.seed,
        start_s=args.warm_up,
    )
    temperatures = run.temperatures_c if args.temperature else None
    sys.stdout.write(
        readings_to_long_csv(
            run.positions, run.dial_angles_deg, run.times_s, temperatures_c=temperatures
        )
    )
    return 0


def add_simulate_command(commands, guarded, say) -> None:
    simulate = commands.add_parser("simulate", help=say("clihelp.simulate"))
    simulate.add_argument("part", nargs="?", choices=["heading", "latitude", "static"])
    simulate.add_argument(
        "--list-presets",
        action="store_true",
        help=say("clihelp.simulate.list_presets"),
    )
    simulate.add_argument("--json", action="store_true", help=say("clihelp.simulate.json"))
    simulate.add_argument("--preset", choices=sorted(PRESETS), default="teaching-fog")
    simulate.add_argument("--latitude", type=float)
    simulate.add_argument("--earth-rate", type=float, default=EARTH_RATE_DEG_H)
    simulate.add_argument(
        "--azimuth",
        type=float,
        default=0.0,
        help=say("clihelp.simulate.azimuth"),
    )
    simulate.add_argument("--seconds-per-position", type=float)
    simulate.add_argument("--seconds", type=float, help=say("clihelp.simulate.seconds"))
    simulate.add_argument("--settle", type=float, default=0.0, help=say("clihelp.simulate.settle"))
    simulate.add_argument("--rate", type=float, help=say("clihelp.simulate.rate"))
    simulate.add_argument("--positions", type=int, default=4)
    simulate.add_argument("--rotation", choices=["ccw", "cw"], default="ccw")
    simulate.add_argument("--pitch", type=float, default=0.0)
    simulate.add_argument("--roll", type=float, default=0.0)
    simulate.add_argument(
        "--elevation",
        type=float,
        default=0.0,
        help=say("clihelp.simulate.elevation"),
    )
    simulate.add_argument(
        "--indexing-sigma", type=float, help=say("clihelp.simulate.indexing_sigma")
    )
    simulate.add_argument("--seed", type=int, default=0)
    simulate.add_argument("--language", choices=["en", "zh-CN"], help=say("clihelp.language"))
    simulate.add_argument(
        "--temperature", action="store_true", help=say("clihelp.simulate.temperature")
    )
    simulate.add_argument(
        "--warm-up",
        type=float,
        default=WARM_GYRO_S,
        metavar="SECONDS",
        help=say("clihelp.simulate.warm_up"),
    )
    simulate.set_defaults(handler=guarded(simulate_command))
