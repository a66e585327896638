"""The angles ``gyrolab solve`` gives each position (a long table's own, else those of
``--rotation``, ``--start-angle`` and ``--step``), and what it says on stderr beside its
output: the rows a table's reader passed over, and a file's angles that run round the
other way from ``--rotation``."""

from __future__ import annotations

import argparse

import numpy as np

from app.core.readings_data import Readings
from app.core.sinusoid import elevation_angles, heading_angles
from app.core.table_headers import angle_list, turned_other_way


def position_angles(part: str, readings: Readings, args: argparse.Namespace) -> np.ndarray:
    """Each position's angle: as the file gives them (a long table), else the nominal ones
    of ``--rotation``, ``--start-angle`` and ``--step`` for the positions' numbers."""
    if readings.angles_deg is not None:
        return np.asarray(readings.angles_deg)
    numbers = np.asarray(readings.numbers or range(1, len(readings.positions) + 1))  # "P3"
    if part == "heading":
        angles = heading_angles(numbers.max(), args.rotation, args.start_angle, args.step)
        return angles[numbers - 1]
    return elevation_angles(numbers.max(), args.start_angle, args.step)[numbers - 1]


def said_beside(part: str, readings: Readings, args: argparse.Namespace) -> list[str]:
    """What ``solve`` says on stderr beside its output: the rows a table's reader passed
    over, and a header's or a long table's angles round the other way from
    ``--rotation``."""
    from app.web.i18n import translator

    say = translator(args.language)
    said = [say(key, **params) for key, params in readings.left_out()]
    header = readings.header_angles
    if header is not None and part == "heading":
        expected = [float(angle) for angle in position_angles(part, readings, args)]
        if turned_other_way(header, expected):
            said.append(
                say(
                    "cli.header_angles_other_way",
                    header=angle_list(header),
                    session=angle_list(expected),
                    count=len(expected),
                    rotation=args.rotation,
                    other="cw" if args.rotation == "ccw" else "ccw",
                )
            )
    if readings.layout == "long" and readings.angles_deg is not None and part == "heading":
        count = len(readings.angles_deg)  # used as given: said where --rotation runs the other way
        turns = heading_angles(count, args.rotation, args.start_angle, args.step).tolist()
        if turned_other_way(readings.angles_deg, turns):
            said.append(
                say(
                    "cli.long_angles_other_way",
                    header=angle_list(readings.angles_deg),
                    session=angle_list(turns),
                    rotation=args.rotation,
                )
            )
    return said
