"""``gyrolab bridge``: the command line of app.bridge (arguments, messages in the user's
language, exit status)."""

from __future__ import annotations

import argparse
import os
import re
import sys
import time
from datetime import datetime
from pathlib import Path

from app.bridge.frames import MAX_RATE_HZ
from app.bridge.instruments import FORMATS, Instrument, set_up
from app.bridge.recording import AXES, Recorder, open_recording, paced
from app.bridge.run import Outcome, SampleTable, run_bridge
from app.bridge.samples import UNITS, SampleMaker
from app.bridge.sources import serial_chunks, stream_chunks
from app.cli.science import check_finite
from app.core.exceptions import UserError

EXIT_GAPS = 3  # the run finished but its record has gaps
# the run started but could not go on (exit 1); every other problem is an argument's (exit 2)
RUN_ERRORS = {"bridge.refused", "bridge.server_lost", "bridge.unreachable", "bridge.giving_up"}
INSTRUMENT_KEYS = ("format", "axis", "unit", "rate_hz", "integrated", "temperature_scale")


def add_bridge_command(commands, say) -> None:
    bridge = commands.add_parser(
        "bridge",
        help=say("clihelp.bridge"),
        description=say("clihelp.bridge.about"),
    )
    source = bridge.add_mutually_exclusive_group()
    source.add_argument("--serial", help=say("clihelp.bridge.serial"))
    source.add_argument("--file", help=say("clihelp.bridge.file"))
    source.add_argument("--replay", help=say("clihelp.bridge.replay"))
    bridge.add_argument(
        "--format",
        help=say("clihelp.bridge.format", formats=" | ".join(FORMATS)),
    )
    bridge.add_argument("--baud", type=int, help=say("clihelp.bridge.baud"))
    bridge.add_argument("--axis", choices=AXES, help=say("clihelp.bridge.axis"))
    bridge.add_argument(
        "--unit",
        choices=list(UNITS),
        help=say("clihelp.bridge.unit"),
    )
    bridge.add_argument("--rate", type=float, help=say("clihelp.bridge.rate"))
    bridge.add_argument(
        "--integrated", action="store_true", default=None, help=say("clihelp.bridge.integrated")
    )
    bridge.add_argument("--temp-scale", type=float, help=say("clihelp.bridge.temp_scale"))
    bridge.add_argument(
        "--regex",
        help=say("clihelp.bridge.regex"),
    )
    bridge.add_argument("--column", type=int, help=say("clihelp.bridge.column"))
    bridge.add_argument("--scale", type=float, help=say("clihelp.bridge.scale"))
    bridge.add_argument("--record", help=say("clihelp.bridge.record"))
    bridge.add_argument("--speed", type=float, default=1.0, help=say("clihelp.bridge.speed"))
    bridge.add_argument("--csv", help=say("clihelp.bridge.csv"))
    bridge.add_argument("--url", default="http://127.0.0.1:8000", help=say("clihelp.bridge.url"))
    bridge.add_argument("--token", help=say("clihelp.bridge.token"))
    bridge.add_argument("--session", type=int, help=say("clihelp.bridge.session"))
    bridge.add_argument("--part", choices=["heading", "latitude"])
    bridge.add_argument("--position", type=int, choices=range(1, 9), metavar="1-8")
    bridge.add_argument("--batch", type=int, default=50, help=say("clihelp.bridge.batch"))
    bridge.add_argument(
        "--json",
        action="store_true",
        help=say("clihelp.bridge.json"),
    )
    bridge.add_argument("--max-samples", type=int, help=say("clihelp.bridge.max_samples"))
    bridge.add_argument("--seconds", type=float, help=say("clihelp.bridge.seconds"))
    bridge.add_argument("--language", choices=["en", "zh-CN"], help=say("clihelp.language"))
    bridge.set_defaults(handler=bridge_command)


def bridge_command(args: argparse.Namespace) -> int:
    from app.web.i18n import normalise, translate

    language = args.language or normalise(os.environ.get("LANG")) or "en"

    def say(key: str, **params: object) -> str:
        return translate(key, language, **params)

    try:
        return _run(args, say)
    except UserError as error:
        print(f"gyrolab bridge: {say(error.key, **error.params)}", file=sys.stderr)
        return 1 if error.key in RUN_ERRORS else 2


def check_options(args: argparse.Namespace) -> None:
    """The command's numbers as the bridge can use them, each refused in words: a rate of
    0 was a traceback, NaN or a negative rate wrote NaN or falling times into the CSV, a
    scale of NaN or 0 and a column of −3 dropped or zeroed every reading without a word."""
    for name, value in (
        ("--rate", args.rate),
        ("--temp-scale", args.temp_scale),
        ("--scale", args.scale),
        ("--speed", args.speed),
        ("--seconds", args.seconds),
    ):
        check_finite(name, value)
    if args.rate is not None and not 0 < args.rate <= MAX_RATE_HZ:
        raise UserError("bridge.bad_rate", name="--rate", most=f"{MAX_RATE_HZ:,.0f}")
    if args.scale == 0:
        raise UserError("bridge.zero_scale", name="--scale")
    if args.speed < 0:  # 0: as fast as the recording can be read
        raise UserError("bridge.negative", name="--speed")
    if args.seconds is not None and args.seconds <= 0:
        raise UserError("bridge.not_positive", name="--seconds")
    for name, value in (
        ("--column", args.column),
        ("--batch", args.batch),
        ("--max-samples", args.max_samples),
        ("--baud", args.baud),
    ):
        if value is not None and value < 1:
            raise UserError("bridge.not_a_count", name=name)


def _run(args: argparse.Namespace, say) -> int:
    check_options(args)
    recording = open_recording(Path(args.replay)) if args.replay else None
    saved = recording.meta if recording else {}
    instrument = _instrument(args, saved)
    uploading = args.session is not None
    if uploading and (args.part is None or args.position is None):
        raise UserError("bridge.needs_target")
    token = args.token or os.environ.get("GYROLAB_TOKEN")
    if uploading and not token:
        raise UserError("bridge.no_token")
    mid_line = bool(saved.get("mid_line", True)) if recording else bool(args.serial)
    setup = set_up(instrument, mid_line=mid_line)
    wall_clock = float(saved.get("wall_clock_s", time.time())) if recording else time.time()
    maker = SampleMaker(
        setup.unit,
        setup.rate_hz,
        integrated=instrument.integrated,
        start_s=seconds_since_midnight(wall_clock),
    )
    baud = args.baud or saved.get("baud") or instrument.default_baud()
    if recording is not None:
        chunks = paced(recording.chunks(), args.speed)
    elif args.serial:
        chunks = serial_chunks(args.serial, int(baud))
    elif args.file and args.file != "-":
        try:
            chunks = stream_chunks(Path(args.file).open("rb"))  # noqa: SIM115 (closed by it)
        except OSError as error:
            raise UserError("bridge.cannot_read", path=args.file, error=error.strerror) from None
    else:
        chunks = stream_chunks(sys.stdin.buffer)
    recorder = None
    if args.record:
        meta = _meta(instrument, args, baud, wall_clock, mid_line)
        recorder = Recorder(Path(args.record), meta)
    table = None
    if args.csv:
        table = SampleTable(
            Path(args.csv),
            args.position or 1,
            timed=setup.rate_hz is not None,
            temperature=setup.has_temperature,
        )

    def progress(outcome: Outcome, stored: int | None, absent: int) -> None:
        text = say(
            "bridge.progress", samples=outcome.samples, stored=_or_dash(stored), absent=absent
        )
        print(f"\r{text}", end="", file=sys.stderr, flush=True)

    import httpx

    with httpx.Client(
        base_url=args.url, headers={"Authorization": f"Bearer {token}"}, timeout=30
    ) as client:
        uploader = None
        if uploading:
            from app.bridge.upload import Uploader

            uploader = Uploader(
                client,
                args.session,
                args.part,
                args.position,
                batch=args.batch,
                binary=not args.json,
            )
        outcome = run_bridge(
            chunks,
            setup,
            maker,
            uploader=uploader,
            recorder=recorder,
            table=table,
            max_samples=args.max_samples,
            seconds=args.seconds,
            progress=progress if sys.stderr.isatty() else None,
        )
    if recording is not None:
        outcome.truncated = recording.truncated
    for line in report(outcome, say, uploading):
        print(line, file=sys.stderr)
    return EXIT_GAPS if outcome.gapped else 0


def _instrument(args: argparse.Namespace, saved: dict) -> Instrument:
    """The instrument from the arguments, a replay's recording filling what is not given."""
    chosen = {
        "format": args.format,
        "axis": args.axis,
        "unit": args.unit,
        "rate_hz": args.rate,
        "integrated": args.integrated,
        "temperature_scale": args.temp_scale,
    }
    for key in INSTRUMENT_KEYS:
        if chosen[key] is None and saved.get(key) is not None:
            chosen[key] = saved[key]
    regex = args.regex if args.regex is not None else saved.get("regex")
    try:
        pattern = re.compile(regex) if regex else None
    except re.error as error:
        raise UserError("bridge.bad_regex", error=str(error)) from None
    column = args.column if args.column is not None else saved.get("column")
    scale = args.scale if args.scale is not None else saved.get("scale", 1.0)
    return Instrument(
        format=chosen["format"] or "text",
        axis=chosen["axis"],
        unit=chosen["unit"],
        rate_hz=chosen["rate_hz"],
        integrated=bool(chosen["integrated"]),
        temperature_scale=chosen["temperature_scale"],
        regex=pattern,
        column=column,
        scale=float(scale),
    )


def _meta(instrument: Instrument, args, baud, wall_clock: float, mid_line: bool) -> dict:
    """What a recording keeps about how it was read (a replay's defaults)."""
    return {
        "format": instrument.format,
        "axis": instrument.axis,
        "unit": instrument.unit,
        "rate_hz": instrument.rate_hz,
        "integrated": instrument.integrated,
        "temperature_scale": instrument.temperature_scale,
        "regex": instrument.regex.pattern if instrument.regex else None,
        "column": instrument.column,
        "scale": instrument.scale,
        "baud": int(baud),
        "source": args.serial or args.file or args.replay or "stdin",
        "mid_line": mid_line,
        "wall_clock_s": wall_clock,
        "started": datetime.fromtimestamp(wall_clock).astimezone().isoformat(timespec="seconds"),
    }


def seconds_since_midnight(wall_clock: float) -> float:
    """The PC clock's local time of day in seconds: the anchor of a run's gyro clock, so
    that positions recorded in separate runs the same day share one clock."""
    moment = datetime.fromtimestamp(wall_clock)
    midnight = moment.replace(hour=0, minute=0, second=0, microsecond=0)
    return (moment - midnight).total_seconds()


def _or_dash(value: int | None) -> object:
    return "—" if value is None else value


def report(outcome: Outcome, say, uploading: bool) -> list[str]:
    """The closing report: counts, gaps, temperature."""
    s = outcome.stats
    lines = [
        say(
            "bridge.summary",
            frames=s.frames,
            samples=outcome.samples,
            stored=outcome.stored if uploading else "—",
        ),
        say(
            "bridge.summary_link",
            corrupt=s.corrupt,
            faults=s.faults,
            repeated=s.repeated,
            missing=s.missing,
            garbage=s.garbage_bytes,
            resyncs=s.resyncs,
        ),
    ]
    if outcome.counted:
        if outcome.gapped:
            lines.append(say("bridge.gapped", n=outcome.gaps, absent=outcome.absent))
        else:
            lines.append(say("bridge.no_gaps"))
    if outcome.temperatures:
        low, high = outcome.temperatures
        lines.append(say("bridge.temperature", low=f"{low:.2f}", high=f"{high:.2f}"))
    if outcome.truncated:
        lines.append(say("bridge.truncated"))
    return lines
