"""A spreadsheet's row of means under a table of readings, written without a label.

A student who types the readings into a spreadsheet often ends each column with
``=AVERAGE(…)``.  With a label beside it ("平均值", "mean") the row is a summary row
(:func:`app.core.table_headers.summary_label`); without one it looks like one more reading.
Kept, it would add a reading equal to the mean: the mean unchanged, n one larger and the
scatter smaller: the σ of the mean √((n − 1)/(n + 1)) of what it is, 10 % too small at
n = 10 -- the honest uncertainty the lab asks for, quietly wrong.  Such a row is told by
how it is written: a spreadsheet writes the mean to more decimals than the readings have.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

MIN_READINGS_ABOVE = 3  # a mean of fewer is no pattern to tell a reading from
_WRITTEN = re.compile(r"[+-]?(\d*)(?:\.(\d*))?(?:[eE]([+-]?\d+))?")


def written_decimals(cell: str, *, significant: bool = False) -> int | None:
    """The decimal places a number is written to: "10.740" → 3, "1.25e-1" → 3, "12" → 0;
    ``significant``, without the zeros that end it: "10.740" → 2.

    Parameters
    ----------
    cell : str
        A plain decimal number (a point, not a comma).
    significant : bool
        Leave out the zeros at the end of the digits after the point (a typed "6.020" is
        written no finer than "6.02").

    Returns
    -------
    int or None
        Digits after the point, less the exponent; None for a cell that is no number.
    """
    match = _WRITTEN.fullmatch(cell.strip())
    if match is None or not (match.group(1) or match.group(2)):
        return None
    fraction = match.group(2) or ""
    if significant:
        fraction = fraction.rstrip("0")
    return len(fraction) - int(match.group(3) or 0)


def is_row_of_means(
    last: Sequence[str], values_above: Sequence[Sequence[float]], decimals_above: Sequence[int]
) -> bool:
    """Whether a table's last row is each column's mean of the rows above it, as a
    spreadsheet's unlabelled ``=AVERAGE`` row writes it.

    It is when, in every column, the cell equals the mean of the readings above to within
    half a unit of its last written decimal, x̄ ∈ [c − ½·10⁻ᵈ, c + ½·10⁻ᵈ], and in one
    column at least it is written to more decimals than any reading above it, zeros at
    the end not counted (a mean of readings to two decimals is 10.7333…; a typed "6.020"
    under "6.02" is no finer).  A reading that does both, in every column, by
    chance has odds far below one in a million: in the column written longer it must hit a
    window 10× or more narrower than the readings' own resolution.

    Parameters
    ----------
    last : sequence of str
        The last row's cell in each position column (plain decimals; "" where empty).
    values_above : sequence of sequences of float
        Each column's readings above the row.
    decimals_above : sequence of int
        The most decimals a reading above is written to, zeros at the end not counted
        (:func:`written_decimals`, ``significant``), per column.

    Returns
    -------
    bool
        True for a row of means; False where a column is empty or has fewer than three
        readings above it.
    """
    longer = False
    for cell, above, most in zip(last, values_above, decimals_above, strict=True):
        decimals = written_decimals(cell) if cell else None
        if decimals is None or len(above) < MIN_READINGS_ABOVE:
            return False
        mean = sum(above) / len(above)
        if abs(float(cell) - mean) > 0.5 * 10.0 ** (-decimals) + 1e-12 * max(1.0, abs(mean)):
            return False
        longer = longer or (written_decimals(cell, significant=True) or 0) > most
    return longer
