"""``gyrolab solve`` / ``simulate`` / ``allan``: the science core on the command line.

Bad input exits with status 2 and one clear line on stderr, never a traceback.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import asdict, replace
from itertools import pairwise

import numpy as np

from app.cli.solve_angles import position_angles, said_beside
from app.core.drift_check import warm_up_message
from app.core.exceptions import UserError
from app.core.explain import explain_heading, explain_latitude
from app.core.gyro_stream import GyroStream
from app.core.jsonsafe import json_safe
from app.core.long_readings import readings_to_long_csv
from app.core.noise_model import GyroNoise, Window, back_to_back
from app.core.presets import PRESETS
from app.core.readings import parse_readings_csv
from app.core.readings_data import Readings
from app.core.record_checks import WARM_UP_LIMIT_C
from app.core.simulate import Setup, simulate_run, simulate_static
from app.core.sinusoid import elevation_angles, heading_angles
from app.core.solve import solve_heading, solve_latitude
from app.core.text_files import decode_text
from app.core.units import (
    DEG_PER_HOUR,
    EARTH_RATE_DEG_H,
    UNITS,
    check_named_unit,
    to_deg_per_hour,
)
from app.core.workbook_sheets import is_workbook
from app.core.workbook_text import workbook_text
from app.core.worked_steps import render_text

WARM_GYRO_S = 3600.0  # simulate's default: a lab gyro is usually left on


class CommandError(Exception):
    """A problem with the command's input: printed as one line, exit status 2."""


def to_json_text(payload: dict) -> str:
    return json.dumps(json_safe(payload), indent=2, ensure_ascii=False, allow_nan=False)


def _read_text(path: str) -> str:
    """The file's text in UTF-8, UTF-16 (by its byte-order mark), GB18030 or Windows-1252,
    or an Excel workbook's sheet of readings, as a page's upload reads it."""
    try:
        if path == "-":
            binary = getattr(sys.stdin, "buffer", None)
            if binary is None:  # a text stream already decoded
                return sys.stdin.read()
            data = binary.read()
        else:
            with open(path, "rb") as handle:
                data = handle.read()
    except FileNotFoundError:
        raise CommandError(f"no such file: {path}") from None
    except OSError as error:
        raise CommandError(f"cannot read {path}: {error.strerror}") from None
    return workbook_text(data) if is_workbook(data) else decode_text(data)


def _finite(name: str, value: float | None) -> None:
    if value is not None and not math.isfinite(value):
        raise CommandError(f"{name} must be a finite number")


def solve_readings(part: str, readings: Readings, args: argparse.Namespace):
    """Solve ``readings`` as the ``solve`` command does (shared with tests and the API)."""
    check_named_unit(readings.named_unit, args.unit)  # °/s read as °/h: 3600 times too small
    unit = args.unit or readings.named_unit or DEG_PER_HOUR
    positions = [to_deg_per_hour(values, unit) for values in readings.positions]
    angles = position_angles(part, readings, args)
    known = _known_noise(readings, positions, getattr(args, "gyro_preset", None))
    known["times_s"] = readings.times_s  # drift fitted (5+ positions) or checked (warm-up)
    known["temperatures_c"] = readings.temperatures_c or None
    if part == "heading":
        expected = None
        if args.latitude is not None and -90 <= args.latitude <= 90:
            expected = args.earth_rate * math.cos(math.radians(args.latitude))
        return solve_heading(
            positions,
            angles,
            true_azimuth_deg=args.true_azimuth,
            expected_amplitude_deg_h=expected,
            **known,
        )
    return solve_latitude(
        positions,
        angles,
        true_latitude_deg=args.latitude,
        true_earth_rate_deg_h=args.earth_rate,
        **known,
    )


def _known_noise(readings: Readings, positions, preset_name: str | None) -> dict:
    """``position_cov`` and ``indexing_sigma_deg`` from a preset's noise model, the windows
    taken from the readings' times (else one after another at the preset's rate)."""
    if preset_name is None:
        return {}
    preset = PRESETS[preset_name]
    noise = GyroNoise.from_preset(preset)
    windows = back_to_back([p.size for p in positions], preset.sample_rate_hz)
    if readings.times_s is not None:
        timed = [
            Window(float(t[0]), float(t[-1] - t[0]) + 1.0 / preset.sample_rate_hz)
            for t in readings.times_s
        ]
        ordered = all(a.end_s <= b.start_s + 1e-9 for a, b in pairwise(timed))
        if ordered and timed[0].start_s >= 0:
            windows = timed
    timed = readings.times_s is not None  # only then is the time since switch-on known
    return {
        "position_cov": noise.mean_covariance(windows, warm_up=timed),
        "indexing_sigma_deg": noise.indexing_sigma_deg,
        "warm_up_cov": noise.warm_up_cov(windows) if timed else None,
    }


def _solve(args: argparse.Namespace) -> int:
    for name in ("start_angle", "step", "latitude", "earth_rate", "true_azimuth"):
        _finite(f"--{name.replace('_', '-')}", getattr(args, name))
    readings = parse_readings_csv(_read_text(args.file), part=args.part)
    result = solve_readings(args.part, readings, args)
    for line in said_beside(args.part, readings, args):  # beside the output, not in it
        print(line, file=sys.stderr)
    warm_up = temperature_summary(readings, args.language)
    if args.json:
        payload = result.to_json()
        if warm_up is not None:
            payload["temperature_c"] = warm_up
        print(to_json_text(payload))
        return 0
    steps = explain_heading(result) if args.part == "heading" else explain_latitude(result)
    from app.web.i18n import translator

    print(render_text(steps, translator(args.language)))
    if warm_up is not None:
        print(warm_up["note"])
    if result.drift_check is not None and result.drift_check.flagged:
        from app.web.i18n import translator

        key, params = warm_up_message(result.drift_check, _wait_minutes(readings, args))
        print(translator(args.language)(key, **params))
    return 0


def _wait_minutes(readings: Readings, args: argparse.Namespace) -> int | None:
    """Minutes until a preset's gyro is warm (five warm-up time constants after switch-on),
    when the times say how long it had been on; else None (a FOG's usual wait)."""
    name = getattr(args, "gyro_preset", None)
    if name is None or readings.times_s is None:
        return None
    tau = PRESETS[name].warmup_time_constant_s
    last = max(float(np.max(t)) for t in readings.times_s if len(t))
    return max(0, math.ceil((5.0 * tau - last) / 60.0)) if tau > 0 else None


def temperature_summary(readings: Readings, language: str = "en") -> dict | None:
    """Mean case temperature per position and a warning (in ``language``) when it changed
    by more than 1 °C while recording: the bias follows the temperature during warm-up."""
    from app.web.i18n import translator

    if not readings.temperatures_c:
        return None
    every = np.concatenate([t for t in readings.temperatures_c if t.size])
    means = [float(t.mean()) if t.size else None for t in readings.temperatures_c]
    change = float(every.max() - every.min()) if every.size else 0.0
    warming = change > WARM_UP_LIMIT_C
    key = "cli.temperature_warming" if warming else "cli.temperature_steady"
    note = translator(language)(key, change=f"{change:.1f}")
    return {"mean_by_position": means, "change": change, "warming_up": warming, "note": note}


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


def _simulate(args: argparse.Namespace) -> int:
    if args.list_presets:
        return _list_presets(args.json)
    if args.part is None:
        raise CommandError("name what to simulate: heading, latitude or static")
    if args.latitude is None:
        raise CommandError("--latitude is required")
    preset = PRESETS[args.preset]
    if args.rate:
        preset = replace(preset, sample_rate_hz=args.rate)
    if args.indexing_sigma is not None:
        preset = replace(preset, indexing_sigma_arcsec=args.indexing_sigma)
    for name in ("latitude", "azimuth", "pitch", "roll", "rate", "seconds", "elevation"):
        _finite(f"--{name}", getattr(args, name))
    if not -90 <= args.latitude <= 90:
        raise CommandError("--latitude must be between -90 and 90 degrees")
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
        _finite("--warm-up", args.warm_up)
        if not 0 <= args.warm_up <= 86_400:
            raise CommandError("--warm-up must be between 0 and 86400 seconds")
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
    if args.positions < 3:
        raise CommandError("--positions must be at least 3")
    seconds = args.seconds_per_position or args.seconds or 10.0
    if seconds <= 0 or seconds * preset.sample_rate_hz > 5_000_000:
        raise CommandError("the dwell time must be positive and under 5 million samples")
    step = 360.0 / args.positions
    if args.part == "heading":
        dials = heading_angles(args.positions, args.rotation, 0.0, step)
    else:
        dials = elevation_angles(args.positions, 0.0, step)
    _finite("--warm-up", args.warm_up)
    if not 0 <= args.warm_up <= 86_400:
        raise CommandError("--warm-up must be between 0 and 86400 seconds")
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


def _guarded(handler):
    def run(args: argparse.Namespace) -> int:
        try:
            return handler(args)
        except UserError as error:
            from app.web.i18n import translator

            language = getattr(args, "language", "en")
            message = translator(language)(error.key, **error.params)
            print(f"gyrolab {args.command}: {message}", file=sys.stderr)
            return 2
        except CommandError as error:
            print(f"gyrolab {args.command}: {error}", file=sys.stderr)
            return 2

    return run


def add_science_commands(commands) -> None:
    solve = commands.add_parser("solve", help="heading, or latitude and Earth rate, from a CSV")
    solve.add_argument("part", choices=["heading", "latitude"])
    solve.add_argument("file", help="CSV file (wide or long layout); '-' reads stdin")
    solve.add_argument(
        "--rotation",
        choices=["ccw", "cw"],
        default="ccw",
        help="heading: direction the table was turned (handout: ccw)",
    )
    solve.add_argument(
        "--start-angle",
        type=float,
        default=0.0,
        help="angle of position 1 (heading: relative azimuth; latitude: "
        "elevation from the north horizon)",
    )
    solve.add_argument("--step", type=float, default=90.0, help="step between positions (deg)")
    solve.add_argument(
        "--unit",
        choices=UNITS,
        default=None,
        help="the readings' unit (default: as the table's header names it, else deg/h)",
    )
    solve.add_argument("--latitude", type=float, help="true latitude φ0 (for percent errors)")
    solve.add_argument(
        "--earth-rate",
        type=float,
        default=EARTH_RATE_DEG_H,
        help="true Earth rate Ω0 in °/h (default 15.041; the handout used 15.04)",
    )
    solve.add_argument("--true-azimuth", type=float, help="true azimuth of position 1 (deg)")
    solve.add_argument(
        "--gyro-preset",
        choices=sorted(PRESETS),
        help="the gyro's noise model (a simulator preset): the 1σ then includes correlated "
        "noise (uncertainty_model 'allan') instead of assuming white noise",
    )
    solve.add_argument("--json", action="store_true")
    solve.add_argument("--language", choices=["en", "zh-CN"], default="en")
    solve.set_defaults(handler=_guarded(_solve))

    simulate = commands.add_parser("simulate", help="simulated gyro readings as long CSV")
    simulate.add_argument("part", nargs="?", choices=["heading", "latitude", "static"])
    simulate.add_argument(
        "--list-presets",
        action="store_true",
        help="print every preset's parameters (with --json: as JSON) and exit",
    )
    simulate.add_argument("--json", action="store_true", help="with --list-presets")
    simulate.add_argument("--preset", choices=sorted(PRESETS), default="teaching-fog")
    simulate.add_argument("--latitude", type=float)
    simulate.add_argument("--earth-rate", type=float, default=EARTH_RATE_DEG_H)
    simulate.add_argument(
        "--azimuth",
        type=float,
        default=0.0,
        help="true azimuth of position 1 (heading) or of the vertical plane",
    )
    simulate.add_argument("--seconds-per-position", type=float)
    simulate.add_argument("--seconds", type=float, help="static: record length")
    simulate.add_argument(
        "--settle", type=float, default=0.0, help="seconds discarded after each turn"
    )
    simulate.add_argument("--rate", type=float, help="sample rate in Hz (default: the preset's)")
    simulate.add_argument("--positions", type=int, default=4)
    simulate.add_argument("--rotation", choices=["ccw", "cw"], default="ccw")
    simulate.add_argument("--pitch", type=float, default=0.0)
    simulate.add_argument("--roll", type=float, default=0.0)
    simulate.add_argument(
        "--elevation",
        type=float,
        default=0.0,
        help="heading/static: axis elevation above the table plane",
    )
    simulate.add_argument("--indexing-sigma", type=float, help="arcsec per turn (default: preset)")
    simulate.add_argument("--seed", type=int, default=0)
    simulate.add_argument(
        "--temperature",
        action="store_true",
        help="add the gyro case temperature (temperature_c, °C; rises during warm-up)",
    )
    simulate.add_argument(
        "--warm-up",
        type=float,
        default=WARM_GYRO_S,
        metavar="SECONDS",
        help="the gyro has been on this long before the first reading (default 3600: a lab "
        "gyro is left on; 0 is a cold start, whose bias still drifts)",
    )
    simulate.set_defaults(handler=_guarded(_simulate))

    from app.cli.allan import add_allan_command
    from app.cli.error_scenarios import add_errors_command

    add_allan_command(commands, _guarded)

    add_errors_command(commands, _guarded, to_json_text)
