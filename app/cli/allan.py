"""``gyrolab allan``: a static record read block by block, prepared (gaps, spikes,
warm-up), its Allan deviation and the IEEE 952 terms it carries, with the dwell advice."""

from __future__ import annotations

import argparse
import sys

from app.cli.science import check_finite, to_json_text, unreadable
from app.core.allan import analyse_record
from app.core.allan_summary import dwell_lines, note_lines, summary_lines, term_rows
from app.core.matlab_files import is_matlab_file, matlab_record
from app.core.numpy_files import is_npy, is_npz, numpy_record
from app.core.static_record import read_static_record
from app.core.text_files import text_lines
from app.core.units import UNITS
from app.core.workbook_sheets import is_workbook
from app.core.workbook_text import workbook_text


def _open_record(path: str):
    """The record's lines, read as the file is parsed (never the whole text at once; an
    Excel workbook's sheet of readings, bounded, whole)."""
    if path == "-":
        binary = getattr(sys.stdin, "buffer", None)
        return text_lines(binary) if binary is not None else iter(sys.stdin)
    try:
        handle = open(path, "rb")  # noqa: SIM115 -- closed when the lines run out
    except OSError as error:
        raise unreadable(path, error) from None

    def lines():
        with handle:
            if is_workbook(handle.read(8)):  # an Excel workbook: its sheet of readings
                handle.seek(0)
                yield from workbook_text(handle.read()).splitlines()
                return
            handle.seek(0)
            yield from text_lines(handle)

    return lines()


def _array_file(path: str, column: str | None):
    """The record of a MATLAB data file or a NumPy array or archive (not read from
    stdin), else None."""
    if path == "-":
        return None
    try:
        with open(path, "rb") as handle:
            magic = handle.read(20)
            if not (is_matlab_file(magic) or is_npy(magic) or is_workbook(magic)):
                return None
            handle.seek(0)
            data = handle.read()
    except OSError as error:
        raise unreadable(path, error) from None
    if is_matlab_file(magic):
        return matlab_record(data, column)
    if is_npy(magic) or is_npz(data):
        return numpy_record(data, column)
    return None  # an Excel workbook: read as text


def _allan(args: argparse.Namespace) -> int:
    from app.web.i18n import translator

    _ = translator(args.language)
    for name in ("rate", "max_tau"):
        check_finite(f"--{name.replace('_', '-')}", getattr(args, name))
    show = args.progress or (sys.stderr.isatty() and not args.json)

    def progress(stage: str, details: dict) -> None:
        if show:
            count = f"{details['samples']:,}"
            print(_(f"allan.progress_{stage}", samples=count), file=sys.stderr, flush=True)

    record = _array_file(args.file, args.column)  # MATLAB's or NumPy's arrays
    if record is None:
        lines = _open_record(args.file)
        record = read_static_record(lines, progress=progress, column=args.column, finite=False)
    result = analyse_record(
        record, args.rate, unit=args.unit, max_tau_s=args.max_tau, progress=progress
    )
    if args.json:
        payload = result.to_json()
        payload["summary"] = {
            "terms": term_rows(payload["terms"], _),
            "dwell": dwell_lines(payload["dwell"], _),
            "notes": note_lines(result.notes, _),
        }
        print(to_json_text(payload))
        return 0
    print(_("allan.heading_curve"))
    for tau, adev, low, high in zip(
        result.taus_s,
        result.adev_deg_h,
        result.band_low_deg_h,
        result.band_high_deg_h,
        strict=True,
    ):
        print(f"{tau:12.3f} {adev:14.6g}   {low:.4g} … {high:.4g}")
    for line in summary_lines(result, _):
        print(line)
    return 0


def add_allan_command(commands, guarded, say) -> None:
    allan = commands.add_parser(
        "allan",
        help=say("clihelp.allan"),
    )
    allan.add_argument(
        "file",
        help=say("clihelp.allan.file"),
    )
    allan.add_argument("--rate", type=float, help=say("clihelp.allan.rate"))
    allan.add_argument(
        "--unit",
        choices=UNITS,
        default=None,
        help=say("clihelp.allan.unit"),
    )
    allan.add_argument(
        "--column",
        metavar="NAME|N",
        help=say("clihelp.allan.column"),
    )
    allan.add_argument(
        "--max-tau", type=float, metavar="SECONDS", help=say("clihelp.allan.max_tau")
    )
    allan.add_argument("--progress", action="store_true", help=say("clihelp.allan.progress"))
    allan.add_argument("--language", choices=["en", "zh-CN"], help=say("clihelp.language"))
    allan.add_argument("--json", action="store_true")
    allan.set_defaults(handler=guarded(_allan))
