"""Readings as written, without their offset: the step they were typed to, offset-free
patterns of a take or a part (for finding copies after an offset or a reordering), and
the handout's own tables as such patterns (app/core/data_evidence.py uses them)."""

from __future__ import annotations

import csv
import hashlib
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

COPY_MIN_READINGS = 8
COPY_MIN_LEVELS = 3  # a copy needs readings that take at least this many values
COPY_MIN_BITS = 32.0  # and Σ n·H bits of pattern (a chance match ≈ 2^−32 per pair of parts)
HANDOUT_MIN_BITS = 12.0  # against the handout's eight columns only: ≈ 8·2^−12 per take
REORDER_LEVELS = 0.6  # reordering is checked when the distinct values are ≥ 60 % of n
HANDOUT = Path(__file__).with_name("data")


def typed_step(values: np.ndarray) -> float | None:
    """The decimal step the values were written to.

    Parameters
    ----------
    values : numpy.ndarray
        Readings.

    Returns
    -------
    float or None
        10⁻ᵈ for the fewest decimals d ≤ 6 that hold every value (0.01 for "10.74"), or
        None for full-precision floats: d holds them when every |x·10ᵈ − round(x·10ᵈ)| <
        10⁻⁹·max(1, |x·10ᵈ|).
    """
    values = np.asarray(values, float).ravel()
    if values.size > _AT_ONCE:  # one decimal count at a time: the least memory
        for decimals in range(_DECIMALS.size):
            if _holds(values * _DECIMALS[decimals]).all():
                return 10.0**-decimals
        return None
    fits = _holds(np.multiply.outer(_DECIMALS, values)).all(axis=1)  # all seven at once
    first = int(np.argmax(fits))
    return 10.0**-first if fits[first] else None


_DECIMALS = 10.0 ** np.arange(7)  # 10ᵈ for d = 0 … 6
_AT_ONCE = 512  # readings up to which typed_step checks every d in one pass


def _holds(scaled: np.ndarray) -> np.ndarray:
    """Whether each scaled value is a whole number to 10⁻⁹ of its size (typed_step)."""
    with np.errstate(invalid="ignore"):
        return np.abs(scaled - np.round(scaled)) < 1e-9 * np.maximum(1.0, np.abs(scaled))


@dataclass(frozen=True)
class Pattern:
    """A take's readings without their offset: whole steps above the smallest reading
    (on the typed step, divided by their common factor so that 10.7, 10.8 and 10.73,
    10.83 read alike; read-only), how much a chance match is ruled out: n·H bits, H the
    entropy of the steps' distribution, and how many distinct steps there are."""

    levels: np.ndarray
    bits: float
    distinct: int

    @property
    def reorderable(self) -> bool:
        """Readings that take many values: a match after sorting still means something."""
        return self.distinct >= REORDER_LEVELS * self.levels.size


REMEMBERED_READINGS = 1024  # patterns of takes up to this size are remembered (below)


def pattern(values: np.ndarray) -> Pattern | None:
    """A take's readings without their offset.

    Parameters
    ----------
    values : numpy.ndarray
        One position's readings.

    Returns
    -------
    Pattern or None
        Its :class:`Pattern`; None for fewer than 8 readings or 3 distinct values.

    Notes
    -----
    A part's patterns are asked for twice (its copy keys, and each position alone against
    the handout's columns, one right after the other), so the last 256 patterns of takes
    of ≤ 1,024 readings are remembered by the readings' bytes (≤ 16 kB each, 4 MB in all).
    """
    values = np.asarray(values, float)
    if values.size < COPY_MIN_READINGS:
        return None
    if values.size <= REMEMBERED_READINGS:
        return _remembered_pattern(values.tobytes())
    return _pattern(values)


@lru_cache(maxsize=256)
def _remembered_pattern(readings: bytes) -> Pattern | None:
    return _pattern(np.frombuffer(readings, dtype=float))


def _pattern(values: np.ndarray) -> Pattern | None:
    spread = float(np.ptp(values))
    step = typed_step(values) or (spread * 1e-6 if spread > 0 else 1.0)  # full floats
    levels = np.round((values - values.min()) / step).astype(np.int64)
    common = int(np.gcd.reduce(levels)) if np.any(levels) else 1
    levels //= max(common, 1)
    levels.flags.writeable = False  # shared by every caller of a remembered pattern
    _, counts = np.unique(levels, return_counts=True)
    if counts.size < COPY_MIN_LEVELS:
        return None
    share = counts / values.size
    return Pattern(levels, values.size * float(-np.sum(share * np.log2(share))), counts.size)


def _digest(arrays: Sequence[np.ndarray]) -> str:
    digest = hashlib.sha256()
    for levels in arrays:
        digest.update(levels.tobytes() + b"|")
    return digest.hexdigest()


def copy_keys(positions: Sequence[np.ndarray], min_bits: float = COPY_MIN_BITS) -> list[str]:
    """Offset-free keys of one part (or of one take, given alone).

    Parameters
    ----------
    positions : sequence of numpy.ndarray
        The positions' readings, in order.
    min_bits : float
        The least Σ n·H a key needs: honest readings quantised to a few steps could
        otherwise share one by chance (about 2^−bits per pair).

    Returns
    -------
    list of str
        The positions' patterns in order, and sorted within each position when every
        position takes many values; empty below ``min_bits``.
    """
    patterns = [pattern(v) for v in positions]
    if not patterns or any(p is None for p in patterns):
        return []
    if sum(p.bits for p in patterns) < min_bits:
        return []
    keys = ["o" + _digest([p.levels for p in patterns])]
    if all(p.reorderable for p in patterns):
        keys.append("s" + _digest([np.sort(p.levels) for p in patterns]))
    return keys


@lru_cache(maxsize=1)
def _handout_keys() -> dict[str, str]:
    """The handout's tables as copy keys.

    Returns
    -------
    dict
        The key of each column of the handout's two tables (at 12 bits: only eight
        columns to match against) → "heading-1" … "latitude-4".
    """
    keys = {}
    for part, name in (("heading", "handout_horizontal.csv"), ("latitude", "handout_vertical.csv")):
        with (HANDOUT / name).open(encoding="utf-8") as handle:
            rows = list(csv.DictReader(handle))
        for column in rows[0]:
            if not column.startswith("position_"):
                continue
            values = np.array([float(row[column]) for row in rows])
            for key in copy_keys([values], HANDOUT_MIN_BITS):
                keys[key] = f"{part}-{column.removeprefix('position_')}"
    return keys


def handout_matches(positions: Sequence[np.ndarray]) -> list[str]:
    """The handout's table columns that any of these positions' readings match.

    Parameters
    ----------
    positions : sequence of numpy.ndarray
        Each position's readings.

    Returns
    -------
    list of str
        "heading-1" … "latitude-4", sorted; empty when none matches after an offset.
    """
    handout = _handout_keys()
    return sorted(
        {
            handout[key]
            for v in positions
            for key in copy_keys([v], HANDOUT_MIN_BITS)
            if key in handout
        }
    )
