"""How a table of readings names its positions, and which of its rows are not readings.

Students copy the handout's table: a header "位置 | 1 | 2 | 3 | 4" (a label, then the
positions' numbers), one row of samples after another, a label "采样值" beside them and a
last row "平均值" of the means.  Others name the columns "P1", "Pos 1", "第1位置", or by the
turntable's angle ("0°, 90°, 180°, 270°").  This module maps such a header to position
columns and tells a summary row (a mean, a standard deviation) from a row of readings.
The layouts themselves are :mod:`app.core.readings`.
"""

from __future__ import annotations

import re

from app.core.readings_data import symmetric_numbers
from app.core.text_files import plain_text
from app.core.typed_numbers import is_number

CHINESE_NUMBERS = {c: n for n, c in enumerate("一二三四五六七八九十", start=1)}
NUMBER = r"(\d+|[一二三四五六七八九十])"
POSITION_NAMES = [
    re.compile(rf"^(?:position|pos\.?|p|位置)\s*[_#.\-]?\s*{NUMBER}\s*号?$"),  # P1, 位置 1
    re.compile(rf"^第\s*{NUMBER}\s*个?\s*位置$"),  # 第1位置, 第一个位置
    re.compile(rf"^{NUMBER}\s*号\s*位置$"),  # 1号位置
    re.compile(rf"^(?:ω|omega)\s*_?\s*{NUMBER}$"),  # the handout's ω1 … ω4, each position's
]
UNIT_SUFFIX = re.compile(r"\s*[(\[（【][^()\[\]（）【】]*[)\]）】]$")  # "(°/h)", "（度/时）"
ANGLE = re.compile(r"^([+-]?\d+(?:\.\d+)?)\s*(?:°|º|˚|度|deg|degrees?)$")
SUMMARY_LABELS = frozenset(
    {
        "平均值",
        "平均",
        "均值",
        "平均数",
        "均方差",
        "标准差",
        "标准偏差",
        "方差",
        "中位数",
        "最大值",
        "最小值",
        "总和",
        "合计",
        "求和",
        "和",
        "极差",
        "误差",
        "mean",
        "average",
        "avg",
        "ave",
        "median",
        "std",
        "stdev",
        "std dev",
        "stddev",
        "sd",
        "σ",
        "sigma",
        "variance",
        "var",
        "sum",
        "total",
        "max",
        "min",
        "maximum",
        "minimum",
        "range",
    }
)  # fmt: skip  (the lab page sends them to the grid's script too)


def _number_of(text: str) -> int:
    return CHINESE_NUMBERS[text] if text in CHINESE_NUMBERS else int(text)


def column_name(cell: str) -> str:
    """A header cell as the layouts name it: "位置1", "Position 1", "P1", "pos. 2",
    "第3位置", "4号位置", "位置一", the handout's "ω1" and "位置1 (°/h)" → "position_1" …
    (a unit in brackets is the student's note; the unit is the form's); other names
    lower-cased.

    Parameters
    ----------
    cell : str
        One cell of the header row.

    Returns
    -------
    str
        ``position_N`` for a position's name, else the cell stripped and lower-cased.
    """
    name = UNIT_SUFFIX.sub("", plain_text(cell).strip().lower())
    for pattern in POSITION_NAMES:
        match = pattern.match(name)
        if match:
            return f"position_{_number_of(match.group(1))}"
    return name


def _angle(cell: str) -> float | None:
    match = ANGLE.match(UNIT_SUFFIX.sub("", plain_text(cell).strip().lower()))
    return float(match.group(1)) if match else None


def evenly_round(angles: list[float], from_zero: bool) -> bool:
    """Whether angles are one turn's N-th apart, in turning order (either way round).

    Parameters
    ----------
    angles : list of float
        The angles in the order written (°).
    from_zero : bool
        Whether the first must be 0°.

    Returns
    -------
    bool
        True for N ≥ 3 angles each 360°/N on from the one before, or each 360°/N back.
    """
    count = len(angles)
    if count < 3 or (from_zero and angles[0] != 0.0):
        return False
    step = 360.0 / count
    turns = [(later - earlier) % 360.0 for earlier, later in zip(angles, angles[1:], strict=False)]
    return any(all(abs(t - way) < 1e-9 for t in turns) for way in (step, 360.0 - step))


def numbered_columns(cells: list[str], more_rows: bool) -> dict[int, int] | None:
    """Position columns of a header that numbers the positions instead of naming them.

    * the handout's "位置 | 1 | 2 | 3 | 4": cells 1, 2, …, N (N ≥ 2) in order, the others
      text (a label, "序号", "time");
    * the turntable's angles, "0° | 90° | 180° | 270°" (or "0度", "0 deg"): N ≥ 3 of
      them, a turn's N-th apart in order, either way round, from any start;
    * a header of numbers alone ("1, 2, 3, 4" or "0, 90, 180, 270") only when N ≥ 3,
      the angles start at 0, and rows follow (otherwise it is a row of readings).

    Parameters
    ----------
    cells : list of str
        The header row's cells.
    more_rows : bool
        Whether rows follow it.

    Returns
    -------
    dict or None
        Column index → position number, or None when the row is no such header.
    """
    return _numbered(cells, more_rows)[0]


def _numbered(
    cells: list[str], more_rows: bool
) -> tuple[dict[int, int] | None, list[float] | None]:
    """:func:`numbered_columns`'s columns, and the angles that head them where they are
    the turntable's (:func:`header_angles`)."""
    stripped = [UNIT_SUFFIX.sub("", plain_text(c).strip()) for c in cells]
    used = [(index, cell) for index, cell in enumerate(stripped) if cell]
    numbers = [(index, cell) for index, cell in used if is_number(cell)]
    angles = [(index, _angle(cell)) for index, cell in used if _angle(cell) is not None]
    labelled = len(used) > len(numbers) + len(angles)  # a text cell: "位置", "序号", "time"
    if not labelled and not more_rows:
        return None, None  # one row of numbers and nothing under it: readings, not a header
    if angles:
        if numbers or not evenly_round([angle for _, angle in angles], from_zero=False):
            return None, None
        columns = {index: k for k, (index, _) in enumerate(angles, start=1)}
        return columns, [angle for _, angle in angles]
    written = [cell for _, cell in numbers]
    counting = written == [str(k) for k in range(1, len(written) + 1)] or (
        all(cell.isdigit() for cell in written)
        and symmetric_numbers([int(cell) for cell in written]) is not None
    )  # "位置 | 1 | 2 | 3 | 4 | 4 | 3 | 2 | 1": the symmetric order, read in column order
    if counting and len(written) >= (2 if labelled else 3):
        return {index: k for k, (index, _) in enumerate(numbers, start=1)}, None
    if evenly_round([float(cell) for cell in written], from_zero=True):  # "0, 90, 180, 270"
        columns = {index: k for k, (index, _) in enumerate(numbers, start=1)}
        return columns, [float(cell) for cell in written]
    return None, None


def header_angles(cells: list[str], more_rows: bool) -> list[float] | None:
    """The turntable's angles a header heads its position columns with, in column order.

    The columns are still read in order as positions 1, 2, …: students head them so for
    a table turned either way ("0°, 90°, 180°, 270°" as the turns made), so the angles
    only serve to say where they disagree with the session's (:func:`turned_other_way`).

    Parameters
    ----------
    cells : list of str
        The header row's cells.
    more_rows : bool
        Whether rows follow it.

    Returns
    -------
    list of float or None
        Each position column's angle (°), or None where the header numbers the positions
        otherwise ("位置 | 1 | 2 | 3 | 4") or is no such header.
    """
    return _numbered(cells, more_rows)[1]


def summary_label(cells: list[str]) -> str | None:
    """The label of a row that summarises the readings instead of holding one: "平均值",
    "mean", "标准差", "σ" … in any of the row's cells (the handout ends its tables with
    a row of means).

    Parameters
    ----------
    cells : list of str
        The cells of the row that are not position columns.

    Returns
    -------
    str or None
        The label as written, or None for a row of readings.
    """
    for cell in cells:
        name = UNIT_SUFFIX.sub("", plain_text(cell).strip()).rstrip(":：").strip()
        if name.lower() in SUMMARY_LABELS:
            return name
    return None


def turned_other_way(given: list[float], expected: list[float]) -> bool:
    """Whether angles go round the other way from the expected ones.

    True where, measured from the first, each given angle is minus the expected one
    (mod 360°) and not the expected one itself: a header "0°, 90°, 180°, 270°" over a
    table turned counter-clockwise, whose positions are at 0°, −90°, −180°, −270°
    (lab-reference §3: angles clockwise positive).  Two positions 180° apart, the same
    either way, are never the other way.

    Parameters
    ----------
    given : list of float
        The angles a table heads its columns with (°), in column order.
    expected : list of float
        The session's angles of the same positions (°), in order.

    Returns
    -------
    bool
        Whether ``given`` runs opposite to ``expected``.
    """
    if len(given) != len(expected) or len(given) < 3:
        return False

    def offsets(angles: list[float], sign: float) -> list[float]:
        return [(sign * (angle - angles[0])) % 360.0 for angle in angles]

    def same(first: list[float], second: list[float]) -> bool:
        return all(
            abs((a - b + 180.0) % 360.0 - 180.0) < 1e-6 for a, b in zip(first, second, strict=True)
        )

    ahead = offsets(given, 1.0)
    return same(ahead, offsets(expected, -1.0)) and not same(ahead, offsets(expected, 1.0))


def angle_list(angles) -> str:
    """Angles as a message quotes them: "0°, -90°, -180°, -270°".

    Parameters
    ----------
    angles : iterable of float
        The angles (°).

    Returns
    -------
    str
        Each as few digits as it needs, with its degree sign, comma-separated.
    """
    return ", ".join(f"{angle:g}°" for angle in angles)
