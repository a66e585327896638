"""The decimals each line of the worked steps writes its numbers to, so that the line,
worked by hand from the numbers written (the means of step 1, x and y, φ), gives the result
it writes: the handout's tan θ and its decimals, x, y, b and the closure d from the means,
tan θ = −y/x of the weighted fit, the lines of φ and Ω, and the percent errors.  The rules
for one number: :mod:`app.core.worked_decimals`; the steps: :mod:`app.core.explain`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from decimal import Decimal, localcontext

import numpy as np

from app.core.worked_decimals import (
    MEANS_DECIMALS,
    MOST_DECIMALS,
    RATIO_DECIMALS,
    by_hand,
    means_decimals,
    ratio_decimals,
)
from app.core.worked_steps import fixed as _f
from app.core.worked_steps import in_formula as _p


def percent_error_line(
    symbol: str, value: float, true: float, decimals: int, percent: float
) -> str:
    """η = |x − x0|/x0 × 100% with the numbers written in: x0 as given, x to ``decimals``
    or, where those give another η than the one written, to the fewest more decimals
    (up to six) that give it -- so that the line, worked by hand, gives its own result
    (φ = 31.24695° written 31.25 gave 21.74 % where η = 21.75 %).

    Parameters
    ----------
    symbol : str
        "φ" or "Ω".
    value, true : float
        The measured and the true value.
    decimals : int
        The decimals x is written to elsewhere in the steps.
    percent : float
        η (%), written to two decimals.

    Returns
    -------
    str
        The line.
    """
    given = f"{true:.6f}".rstrip("0")
    given = given + "0" * max(0, decimals - len(given.split(".")[1]))  # "15.04" → "15.040"
    written = _f(percent, 2)
    shown = next(
        (
            digits
            for digits in range(decimals, 7)
            if _f(abs(round(value, digits) - float(given)) / abs(float(given)) * 100, 2) == written
        ),
        decimals,
    )
    measured = f"({_f(value, shown)})" if value < 0 else _f(value, shown)
    if true < 0:  # a southern latitude: η over its size
        return (
            f"η_{symbol} = |{symbol} − {symbol}0|/|{symbol}0| × 100% = "
            f"|{measured} − ({given})| / |{given}| × 100% = {written}%"
        )
    return (
        f"η_{symbol} = |{symbol} − {symbol}0|/{symbol}0 × 100% = "
        f"|{measured} − {given}| / {given} × 100% = {written}%"
    )


def handout_ratio(
    means: np.ndarray, turn: int, decimals: int = MEANS_DECIMALS
) -> tuple[str, str, float]:
    """The handout's tan θ from four position means.

    Parameters
    ----------
    means : numpy.ndarray
        ω1 … ω4 (°/h).
    turn : int
        +1 for positions turned clockwise, −1 counter-clockwise.
    decimals : int
        The decimals the means are substituted with.

    Returns
    -------
    (str, str, float)
        The formula with the means substituted, its numerator ("ω2 − ω4" or "ω4 − ω2"),
        and tan θ (∞ when ω1 = ω3).
    """
    w1, w2, w3, w4 = means
    d = decimals
    if turn < 0:
        top, sub_top, numerator = "ω4 − ω2", f"{_p(w4, d)} − {_p(w2, d)}", w4 - w2
    else:
        top, sub_top, numerator = "ω2 − ω4", f"{_p(w2, d)} − {_p(w4, d)}", w2 - w4
    formula = f"tan θ = ({top}) / (ω1 − ω3) = ({sub_top}) / ({_p(w1, d)} − {_p(w3, d)})"
    return formula, top, numerator / (w1 - w3) if w1 != w3 else math.inf


def ratio_decimals_or_usual(ratio: float, angle_deg: float) -> int:
    """:func:`app.core.worked_decimals.ratio_decimals` for a finite ratio.

    Parameters
    ----------
    ratio : float
        tan θ, perhaps ∞.
    angle_deg : float
        θ as written.

    Returns
    -------
    int
        The decimals to write the ratio to; four for ∞.
    """
    return ratio_decimals(ratio, angle_deg) if math.isfinite(ratio) else RATIO_DECIMALS


def same_ratio(ratio: float, decimals: int, turn: int) -> Callable[[list[Decimal]], bool]:
    """A check of the handout's ratio worked by hand.

    Parameters
    ----------
    ratio : float
        tan θ from the exact means (∞ where ω1 = ω3).
    decimals : int
        The decimals it is written to.
    turn : int
        +1 or −1, as :func:`handout_ratio`.

    Returns
    -------
    callable
        Given the means as written, whether they give ``ratio`` to ``decimals``.
    """

    def check(written: list[Decimal]) -> bool:
        if not math.isfinite(ratio):
            return written[0] == written[2]
        if written[0] == written[2]:
            return False
        by_hand_ratio = handout_ratio(np.array([float(w) for w in written]), turn)[2]
        return _f(by_hand_ratio, decimals) == _f(ratio, decimals)

    return check


def heading_decimals(
    means: np.ndarray,
    turn: int,
    ratio: float,
    ratio_at: int,
    closed: tuple[float, float, float, float | None, float] | None,
) -> tuple[int, tuple[int, int, int]]:
    """The decimals of part A's lines worked from the means.

    Parameters
    ----------
    means : numpy.ndarray
        ω1 … ω4 (°/h).
    turn : int
        +1 or −1, as :func:`handout_ratio`.
    ratio : float
        tan θ from the exact means.
    ratio_at : int
        The decimals tan θ is written to.
    closed : tuple or None
        The handout's closed form where it is the result (equal numbers of readings): x,
        y, b, the closure d (None where not shown) and A1 (°) as the result has them.

    Returns
    -------
    (int, (int, int, int))
        The decimals of the means for which the ratio's line and the lines
        x = (ω1 − ω3)/2, y = ±(ω2 − ω4)/2, b = (ω1 + ω2 + ω3 + ω4)/4 and
        d = (ω1 + ω3 − ω2 − ω4)/2 work out by hand; and the decimals of x and y (four),
        of b and of d (three) -- each a decimal or two more where a half in the next
        makes it ambiguous.
    """
    usual = (4, 3, 3)
    ratio_holds = same_ratio(ratio, ratio_at, turn)
    found: list[tuple[int, int, int]] = []

    def check(written: list[Decimal]) -> bool:
        if not ratio_holds(written):
            return False
        if closed is None:
            return True
        w1, w2, w3, w4 = written
        x, y = (w1 - w3) / 2, ((w2 - w4) if turn < 0 else (w4 - w2)) / 2
        lines = [
            [(x, closed[0]), (y, closed[1])],
            [((w1 + w2 + w3 + w4) / 4, closed[2])],
            [((w1 + w3 - w2 - w4) / 2, closed[3])] if closed[3] is not None else [],
        ]
        decimals = []
        for group, (pairs, fewest) in enumerate(zip(lines, usual, strict=True)):
            at = next(
                (
                    at
                    for at in range(fewest, MOST_DECIMALS + 1)
                    if all(by_hand(hand, at) == _f(value, at) for hand, value in pairs)
                    and (group or same_azimuth(_f(closed[0], at), _f(closed[1], at), closed[4]))
                ),
                None,
            )
            if at is None:
                return False
            decimals.append(at)
        found.append((decimals[0], decimals[1], decimals[2]))
        return True

    decimals = means_decimals(means, check)
    if decimals is None:
        return MEANS_DECIMALS, usual
    return decimals, found[-1] if found else usual


def same_azimuth(x: str, y: str, azimuth_deg: float) -> bool:
    """Whether A1 = atan2(y, x), worked by hand from x and y as written, gives the azimuth
    to its two decimals.

    Parameters
    ----------
    x, y : str
        The components as written.
    azimuth_deg : float
        A1 as the result has it, in [0°, 360°).

    Returns
    -------
    bool
        True where they agree.
    """
    by_hand_azimuth = math.degrees(math.atan2(float(y), float(x))) % 360.0
    return _f(by_hand_azimuth, 2) == _f(azimuth_deg, 2)


def fit_decimals(a: float, c: float, phi_deg: float, omega: float) -> int:
    """The decimals of the fit's a and c for the line φ = atan2(c, a), Ω = √(a² + c²).

    Parameters
    ----------
    a, c : float
        The fit's cosine and sine terms (°/h).
    phi_deg, omega : float
        φ (°, two decimals) and Ω (°/h, three) as the result has them.

    Returns
    -------
    int
        The fewest decimals (four to six) of a and c from which both work out by hand;
        four where none does.
    """
    for decimals in range(4, MOST_DECIMALS + 1):
        a_written, c_written = _f(a, decimals), _f(c, decimals)
        if _f(math.degrees(math.atan2(float(c_written), float(a_written))), 2) != _f(phi_deg, 2):
            continue
        with localcontext() as context:
            context.prec = 40
            size = (Decimal(a_written) ** 2 + Decimal(c_written) ** 2).sqrt()
        if by_hand(size, 3) == _f(omega):
            return decimals
    return 4


def slope_decimals(
    x: float, y: float, slope: float, slope_at: int, azimuth_deg: float | None = None
) -> int:
    """The decimals of the weighted fit's x and y for the line tan θ = −y/x.

    Parameters
    ----------
    x, y : float
        The components (°/h).
    slope : float
        −y/x as the result has it.
    slope_at : int
        The decimals the slope is written to.
    azimuth_deg : float, optional
        A1, which atan2(y, x) must give too.

    Returns
    -------
    int
        The fewest decimals (four to six) of x and y for which −y/x (and A1), worked by
        hand from them, give the slope as written; four where none does (x near 0).
    """
    if not math.isfinite(slope):
        return 4
    for decimals in range(4, MOST_DECIMALS + 1):
        x_written, y_written = Decimal(_f(x, decimals)), Decimal(_f(y, decimals))
        if x_written == 0 or by_hand(-y_written / x_written, slope_at) != _f(slope, slope_at):
            continue
        if azimuth_deg is None or same_azimuth(str(x_written), str(y_written), azimuth_deg):
            return decimals
    return 4


def latitude_decimals(
    means: np.ndarray,
    ratio: float,
    ratio_at: int,
    omega: float,
    phi: float,
    by_cos: float | None,
    by_sin: float | None,
) -> tuple[int, int]:
    """The decimals of part B's lines worked from the means.

    Parameters
    ----------
    means : numpy.ndarray
        ω1 … ω4 at e = 0°, 90°, 180°, 270° (°/h).
    ratio : float
        tan φ from the exact means (∞ where ω1 = ω3).
    ratio_at : int
        The decimals tan φ is written to.
    omega : float
        Ω as the result has it.
    phi : float
        φ as the result has it (°).
    by_cos, by_sin : float or None
        Ω = (ω1 − ω3)/(2 cos φ) and (ω2 − ω4)/(2 sin φ), None where not shown.

    Returns
    -------
    (int, int)
        The decimals of the means, and of φ in the lines of Ω, for which tan φ and the
        three lines of Ω (three decimals) work out by hand.
    """
    omega_written = _f(omega)
    for phi_at in range(2, MOST_DECIMALS + 1):
        phi_written = math.radians(float(_f(phi, phi_at)))

        def check(written: list[Decimal], phi_written: float = phi_written) -> bool:
            w1, w2, w3, w4 = written
            if math.isfinite(ratio) and (
                w1 == w3 or _f(float((w2 - w4) / (w1 - w3)), ratio_at) != _f(ratio, ratio_at)
            ):
                return False
            with localcontext() as context:
                context.prec = 40
                if by_hand(((w1 - w3) ** 2 + (w2 - w4) ** 2).sqrt() / 2, 3) != omega_written:
                    return False
                for value, difference, trig in (
                    (by_cos, w1 - w3, math.cos(phi_written)),
                    (by_sin, w2 - w4, math.sin(phi_written)),
                ):
                    if value is None:
                        continue
                    if by_hand(difference / (2 * Decimal(trig)), 3) != _f(value):
                        return False
            return True

        decimals = means_decimals(means, check)
        if decimals is not None:
            return decimals, phi_at
    return MEANS_DECIMALS, 2
