"""The instrument's output step as the class's readings show it (lab-reference §6).

A digital gyro shows whole multiples of one step q: angle pulses over one sample, or the
last digit of its display.  For the simulated gyro q is known
(:func:`app.core.data_evidence.off_grid`); for a real gyro the teacher characterised it
is not, but a class that recorded the same instrument shows it: most groups' readings lie
on one grid, and readings typed by hand keep to it when rounded (a rounded reading is
within half its typed step of a multiple of q).  Readings made up by hand, averaged or
smoothed fall between the steps.

:func:`class_step` finds q from the class, :func:`part_candidate` proposes it from one
part; the part is then tested with ``off_grid``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from app.core.data_copies import typed_step

GRID_SUPPORT = 0.8  # the share of the class's parts that lie on the step
GRID_MIN_PARTS = 8  # and at least this many parts (two positions' worth of four groups)
ON_GRID_SHARE = 0.8  # a part lies on a step when this share of its readings do
MIN_LEVELS = 3  # a part proposes a step when its readings take at least 3 values


def on_step(values: np.ndarray, step: float, typed: float | None = None) -> float:
    """The share of readings within half their typed step of a whole multiple of ``step``.

    Parameters
    ----------
    values : numpy.ndarray
        One part's readings (°/h).
    step : float
        A candidate output step q (°/h).
    typed : float, optional
        The readings' typed step u where the caller knows it (``typed_step``, 0 for
        full-precision numbers).

    Returns
    -------
    float
        The share of readings x with |x − q·round(x/q)| ≤ u/2 + 10⁻⁶·q, u the readings'
        typed step (0 for full-precision numbers); 1.0 when q < 2u (rounding to u hides
        any grid as fine as that).
    """
    if values.size == 0 or step <= 0:
        return 0.0
    if typed is None:
        typed = typed_step(values) or 0.0
    if step < 2.0 * typed:
        return 1.0
    distance = np.abs(values - step * np.round(values / step))
    return float(np.mean(distance <= typed / 2.0 + 1e-6 * step))


def part_candidate(values: np.ndarray) -> float | None:
    """The output step one part's readings suggest: the smallest gap between its distinct
    readings, when at least 80 % of them lie on it.

    Parameters
    ----------
    values : numpy.ndarray
        One part's readings, every position together (°/h).

    Returns
    -------
    float or None
        The step (°/h), rounded to 9 significant digits so that parts of one grid agree;
        None for fewer than three distinct readings or readings on no common step.
    """
    distinct = np.unique(values[np.isfinite(values)])
    if distinct.size < MIN_LEVELS:
        return None
    gaps = np.diff(distinct)
    step = float(np.min(gaps))
    # a gap below a millionth of the spread is a float's noise, not a grid
    if step <= 1e-6 * float(distinct[-1] - distinct[0]) or on_step(values, step) < ON_GRID_SHARE:
        return None
    return float(f"{step:.9g}")


@dataclass(frozen=True)
class GridPart:
    """One part's readings with what the class step asks of them, found once: its typed
    step u (0 for full-precision numbers) and the step it proposes (None if none)."""

    values: np.ndarray
    typed: float
    candidate: float | None

    @classmethod
    def of(cls, values: np.ndarray) -> GridPart:
        values = np.asarray(values, float)
        typed = (typed_step(values) or 0.0) if values.size else 0.0
        return cls(values, typed, part_candidate(values))


def is_decimal_step(step: float) -> bool:
    """Whether ``step`` is 1, 2 or 5 times a power of ten: a step people round to.

    Parameters
    ----------
    step : float
        A candidate output step q > 0 (°/h).

    Returns
    -------
    bool
        True when q = m·10ᵏ with m ∈ {1, 2, 5} (to 10⁻⁶), k = ⌊log₁₀ q⌋.
    """
    exponent = math.floor(math.log10(step))
    mantissa = step / 10.0**exponent
    return any(abs(mantissa - m) < 1e-6 for m in (1.0, 2.0, 5.0, 10.0))


def class_step(parts: Sequence[np.ndarray | GridPart], model_step: float = 0.0) -> float | None:
    """The class's output step: the coarsest step proposed by some part on which at least
    80 % of the class's parts (and at least 8) lie.

    Parameters
    ----------
    parts : sequence of numpy.ndarray or GridPart
        Every part of the class the students recorded themselves (each its positions'
        readings together, °/h), or its :class:`GridPart` where the caller keeps one
        (the proposal sorts every reading).
    model_step : float
        The rate step of the station's noise model, q_m = 3600·LSB·f (°/h), from its
        Allan characterisation's quantisation term; 0 when it has none.

    Returns
    -------
    float or None
        q (°/h), or None when no step is shared that widely -- several instruments, a
        gyro with unquantised output, or too few parts.  A step of 1, 2 or 5 × 10ᵏ is
        also what a class rounds to (most type two decimals of a finer display, a few
        three), so it is taken for the instrument's only when the model's own step
        agrees with it within a factor of 2.

    Notes
    -----
    The coarsest supported step, not the finest: every reading of a 0.1 °/h grid is also
    on a 0.01 °/h grid, so the finest step shared by everyone says nothing.  A part whose
    typed step is coarser than half a candidate supports it trivially (rounding hides the
    grid), so a class that rounded everything to one decimal proposes its rounding, and
    the test of a part (``off_grid``) is skipped where q < 2u.
    """
    found = [p if isinstance(p, GridPart) else GridPart.of(p) for p in parts]
    found = [p for p in found if p.values.size]
    if len(found) < GRID_MIN_PARTS:
        return None
    proposed = sorted({p.candidate for p in found if p.candidate is not None}, reverse=True)
    for step in proposed:
        if is_decimal_step(step) and not (model_step > 0 and 0.5 <= step / model_step <= 2.0):
            continue
        support = sum(on_step(p.values, step, p.typed) >= ON_GRID_SHARE for p in found)
        if support >= GRID_MIN_PARTS and support >= GRID_SUPPORT * len(found):
            return step
    return None
