"""``gyrolab solve`` (and, from their own modules, ``simulate``, ``allan``, ``errors``): the
science core on the command line.

Bad input exits with status 2 and one clear line on stderr, never a traceback.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from itertools import pairwise

import numpy as np

from app.cli.language import command_language
from app.cli.solve_angles import position_angles, said_beside
from app.core.array_text import array_file_text, is_array_file
from app.core.drift_check import warm_up_message
from app.core.exceptions import UserError
from app.core.explain import explain_heading, explain_latitude
from app.core.jsonsafe import json_safe
from app.core.noise_model import GyroNoise, Window, back_to_back
from app.core.presets import PRESETS
from app.core.readings import parse_readings_csv
from app.core.readings_data import Readings
from app.core.record_checks import WARM_UP_LIMIT_C
from app.core.record_kinds import written_as_a_record
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


class CommandError(UserError):
    """A problem with the command's input (a ``cli.*`` message key): printed as one line
    in the command's language, exit status 2."""


def unreadable(path: str, error: OSError) -> CommandError:
    """Why a file could not be opened, in words the catalogue has in both languages."""
    if isinstance(error, FileNotFoundError):
        return CommandError("cli.no_such_file", path=path)
    if isinstance(error, IsADirectoryError):
        return CommandError("cli.is_a_folder", path=path)
    if isinstance(error, PermissionError):
        return CommandError("cli.no_permission", path=path)
    return CommandError("cli.cannot_read", path=path, reason=error.strerror or str(error))


def to_json_text(payload: dict) -> str:
    return json.dumps(json_safe(payload), indent=2, ensure_ascii=False, allow_nan=False)


def _read_text(path: str) -> str:
    """The file's text in UTF-8, UTF-16 (with or without its mark), GB18030 or Windows-1252,
    an Excel workbook's sheet of readings, or a MATLAB or NumPy file's vectors, as the lab
    page reads it."""
    try:
        if path == "-":
            binary = getattr(sys.stdin, "buffer", None)
            if binary is None:  # a text stream already decoded
                return sys.stdin.read()
            data = binary.read()
        else:
            with open(path, "rb") as handle:
                data = handle.read()
    except OSError as error:
        raise unreadable(path, error) from None
    if is_array_file(data):  # MATLAB or NumPy: p1 … p4 a table, one vector a record
        return array_file_text(data)
    return workbook_text(data) if is_workbook(data) else decode_text(data)


def check_finite(name: str, value: float | None) -> None:
    if value is not None and not math.isfinite(value):
        raise CommandError("cli.not_finite", name=name)


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
        check_finite(f"--{name.replace('_', '-')}", getattr(args, name))
    # the station as the lab's pages and the API take it
    if args.latitude is not None and not -90.0 <= args.latitude <= 90.0:
        raise CommandError("cli.latitude_range")
    if not 0.0 < args.earth_rate < 1000.0:
        raise CommandError("cli.earth_rate_range")
    text = _read_text(args.file)
    if written_as_a_record(text):  # its header a comment, LabVIEW's, a MATLAB vector's
        # one position's record: read as a table, its time and axis columns were positions
        raise CommandError("cli.solve_one_record", path=args.file)
    readings = parse_readings_csv(text, part=args.part)
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


def _guarded(handler):
    def run(args: argparse.Namespace) -> int:
        args.language = command_language(args)
        try:
            return handler(args)
        except UserError as error:  # a CommandError too
            from app.web.i18n import translator

            message = translator(args.language)(error.key, **error.params)
            print(f"gyrolab {args.command}: {message}", file=sys.stderr)
            return 2

    return run


def add_science_commands(commands, say) -> None:
    solve = commands.add_parser("solve", help=say("clihelp.solve"))
    solve.add_argument("part", choices=["heading", "latitude"])
    solve.add_argument("file", help=say("clihelp.solve.file"))
    solve.add_argument(
        "--rotation",
        choices=["ccw", "cw"],
        default="ccw",
        help=say("clihelp.solve.rotation"),
    )
    solve.add_argument(
        "--start-angle",
        type=float,
        default=0.0,
        help=say("clihelp.solve.start_angle"),
    )
    solve.add_argument("--step", type=float, default=90.0, help=say("clihelp.solve.step"))
    solve.add_argument(
        "--unit",
        choices=UNITS,
        default=None,
        help=say("clihelp.solve.unit"),
    )
    solve.add_argument("--latitude", type=float, help=say("clihelp.solve.latitude"))
    solve.add_argument(
        "--earth-rate",
        type=float,
        default=EARTH_RATE_DEG_H,
        help=say("clihelp.solve.earth_rate"),
    )
    solve.add_argument("--true-azimuth", type=float, help=say("clihelp.solve.true_azimuth"))
    solve.add_argument(
        "--gyro-preset",
        choices=sorted(PRESETS),
        help=say("clihelp.solve.gyro_preset"),
    )
    solve.add_argument("--json", action="store_true")
    solve.add_argument("--language", choices=["en", "zh-CN"], help=say("clihelp.language"))
    solve.set_defaults(handler=_guarded(_solve))

    from app.cli.allan import add_allan_command
    from app.cli.error_scenarios import add_errors_command
    from app.cli.simulate import add_simulate_command

    add_simulate_command(commands, _guarded, say)
    add_allan_command(commands, _guarded, say)
    add_errors_command(commands, _guarded, to_json_text, say)
