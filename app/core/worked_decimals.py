"""How many decimals a worked line writes its numbers to, so that the line, worked by hand
from the numbers written, gives the result it writes.

A mean of ten readings written to three decimals is exact for readings of two (the
handout's), but not for a FOG's readings of three or more: x = (ω1 − ω3)/2 and the ratio
tan θ = (ω2 − ω4)/(ω1 − ω3), written from the exact means, then differ by hand in their last
digit in most sessions, and arctan of the ratio to four decimals misses θ's second decimal
in about one in thirteen.  The steps (:mod:`app.core.explain`) write the means and the
ratio to the fewest more decimals that make each line give its own result.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from decimal import ROUND_HALF_UP, Decimal, localcontext

import numpy as np

from app.core.worked_steps import fixed

MEANS_DECIMALS = 3  # the decimals the steps write a mean to, at the fewest
RATIO_DECIMALS = 4  # … and a ratio such as tan θ
MOST_DECIMALS = 6  # a mean never needs more: readings are never finer than 10⁻⁶ °/h


def ratio_decimals(ratio: float, angle_deg: float, angle_decimals: int = 2) -> int:
    """The fewest decimals (four to eight) to write ``ratio`` to so that its arctangent
    gives ``angle_deg`` to ``angle_decimals``, as the line "θ = arctan(r) = θ" says.

    Parameters
    ----------
    ratio : float
        tan θ (or tan φ), finite.
    angle_deg : float
        The angle the line writes, in degrees, in (−90°, 90°).
    angle_decimals : int
        The decimals it is written to.

    Returns
    -------
    int
        Four where no count up to eight gives it (an angle written from a rounding tie).
    """
    target = fixed(angle_deg, angle_decimals)
    for decimals in range(RATIO_DECIMALS, 9):
        shown = float(fixed(ratio, decimals))
        if fixed(math.degrees(math.atan(shown)), angle_decimals) == target:
            return decimals
    return RATIO_DECIMALS


def means_decimals(
    means: Sequence[float] | np.ndarray, reproduces: Callable[[list[Decimal]], bool]
) -> int | None:
    """The fewest decimals (three to six) to write the means to so that each line worked
    from them gives its own result.

    Parameters
    ----------
    means : sequence of float
        The positions' means, °/h.
    reproduces : callable
        Given the means as written (exact decimals, as a student reads them), whether
        every line worked from them gives the number it writes.

    Returns
    -------
    int or None
        The decimals; None where no count up to six does.
    """
    for decimals in range(MEANS_DECIMALS, MOST_DECIMALS + 1):
        if reproduces([Decimal(fixed(float(value), decimals)) for value in means]):
            return decimals
    return None


def by_hand(value: Decimal, decimals: int) -> str:
    """A number worked by hand, written to ``decimals`` as a student rounds: a half away
    from zero ("0.44645" → "0.4465").

    Parameters
    ----------
    value : Decimal
        The exact result of the hand's arithmetic.
    decimals : int
        The decimals it is written to.

    Returns
    -------
    str
        As :func:`app.core.worked_steps.fixed` writes a number.
    """
    return str(value.quantize(Decimal(1).scaleb(-decimals), rounding=ROUND_HALF_UP))


def hypot_decimals(x: str, y: str, size: float) -> int:
    """The fewest decimals (three to six) to write ``size`` to so that √(x² + y²), worked by
    hand from x and y as written, gives it.

    Parameters
    ----------
    x, y : str
        The components as the steps write them ("9.8285").
    size : float
        The size the result uses, H (°/h).

    Returns
    -------
    int
        Three where no count up to six gives it.
    """
    with localcontext() as context:
        context.prec = 40
        by_hand_size = (Decimal(x) ** 2 + Decimal(y) ** 2).sqrt()
        for decimals in range(MEANS_DECIMALS, MOST_DECIMALS + 1):
            if by_hand(by_hand_size, decimals) == fixed(size, decimals):
                return decimals
    return MEANS_DECIMALS
