"""Whether a file can only be one position's record, never a table of positions: its header
is the comment line above its readings (EuRoC, Kalibr, ROS), its first line names its times
(a logger's, a phone's export), it is LabVIEW's measurement file, an instrument's captured
sentences or a serial monitor's stamped capture.  The lab page and ``gyrolab solve`` ask
before reading a file as the handout's table (:mod:`app.core.readings`).
"""

from __future__ import annotations

import io
import itertools

from app.core.column_names import comment_text
from app.core.labview_lvm import is_labview_measurement
from app.core.monitor_stamps import is_stamped_capture
from app.core.record_columns import names_a_records_times
from app.core.record_lines import LOOK_AHEAD_LINES, line_splitter
from app.core.record_preamble import header_in_comment, holds_a_number
from app.core.sentence_records import is_sentence_record
from app.core.table_headers import column_name
from app.core.text_files import first_texts
from app.core.typed_numbers import is_number


def written_as_a_record(text: str) -> bool:
    """Whether a file can only be one record, never a table of positions: its header is
    the comment line above its readings (:func:`names_its_columns_in_a_comment`) or a
    first line naming its times (:func:`names_its_times_in_its_header`), it is
    LabVIEW's measurement file (:mod:`app.core.labview_lvm`), an instrument's captured
    sentences (:mod:`app.core.sentence_records`), or a serial monitor's stamped capture
    (:mod:`app.core.monitor_stamps`).

    Parameters
    ----------
    text : str
        The file's text (its first lines are enough).

    Returns
    -------
    bool
        True for any of them.
    """
    return (
        is_labview_measurement(text[:200])
        or names_its_columns_in_a_comment(text)
        or names_its_times_in_its_header(text)
        or is_sentence_record(io.StringIO(text))
        or is_stamped_capture(io.StringIO(text))
    )


def names_its_columns_in_a_comment(text: str) -> bool:
    """Whether a file's header is the comment line just above its readings, as EuRoC,
    Kalibr and ROS write it ("#timestamp [ns],w_RS_S_x [rad s^-1],…"): a record, whose
    columns are named -- not a table of positions whose comments are passed over.

    Parameters
    ----------
    text : str
        The file's text (its first lines are enough).

    Returns
    -------
    bool
        True where the last comment line before the first reading names as many columns
        as that reading has, two of them not positions' ("位置1", "P2": the handout's
        table, its header commented out).
    """
    comment = None
    for line in itertools.islice(io.StringIO(text), LOOK_AHEAD_LINES):
        stripped = line.strip().lstrip("\ufeff")
        if not stripped:
            continue
        if (remark := comment_text(stripped)) is not None:
            comment = remark
            continue
        split = line_splitter(stripped)
        cells = split(stripped)
        names = header_in_comment(comment, split, len(cells))
        if not holds_a_number(cells) or names is None:
            return False
        # "#position_1,position_2,…" heads the handout's table, commented out: positions
        return sum(column_name(name).startswith("position_") for name in names) < 2
    return False


def names_its_times_in_its_header(text: str) -> bool:
    """Whether a file's first line is a header naming a time column above readings of as
    many columns ("Time (ms),X_GYRO (deg/s),…", "time,gx,gy,gz", phyphox's and Sensor
    Logger's exports): one position's record -- a table of positions names its positions,
    never a time beside them (:func:`app.core.record_columns.names_a_records_times`).

    Parameters
    ----------
    text : str
        The file's text (its first lines are enough).

    Returns
    -------
    bool
        True where the first line names a time column and the second holds a number in
        each of as many cells.
    """
    lines = first_texts(itertools.islice(io.StringIO(text), LOOK_AHEAD_LINES), 2)
    if len(lines) < 2 or comment_text(lines[0]) is not None:
        return False
    split = line_splitter(lines[0])
    header, first = split(lines[0]), split(lines[1])
    return (
        len(header) == len(first)
        and all(is_number(cell) for cell in first)
        and names_a_records_times(header)
    )
