"""Evidence that readings came from the instrument: checks a teacher can act on, each with
its numbers, none an accusation (lab-reference §6 for the noise model).

Each check compares one take (one position's readings) or one part (its positions) with
what the station's gyro -- its noise model, or the simulated gyro's preset -- makes:

* **scatter**: the readings' spread against the model's.  For a stationary gyro the
  expected sample variance of n readings is E[s²] = n/(n − 1)·(σ₁² − σ²_mean), σ₁² the
  variance of one reading and σ²_mean that of their mean (both from
  :meth:`GyroNoise.mean_covariance`), plus u²/12 for typed values rounded to a step u
  coarser than the gyro's own.  With ν = Σ(n_i − 1) over the part's positions,
  ν·s²_pooled/E[s²] is close to χ²_ν; far outside it the readings are smoother (invented,
  smoothed) or noisier than the gyro makes.
* **smoothness**: the lag-1 autocorrelation r₁ of the readings (each position's mean
  removed) against the model's ρ₁ = Cov(x_i, x_i+1)/σ₁²; a running average raises it, so
  r₁ − ρ₁ above a few 1/√N is flagged.
* **last digits** (typed readings): the last typed digit is uniform when the scatter is
  several steps wide; Pearson's χ² with 9 degrees of freedom.
* **off the grid** (the simulated gyro): its readings are whole multiples of its output
  step (angle pulses over one sample); typed ones rounded to a finer step stay on it.
* **copies** (offset-free patterns, ``app.core.data_copies``): a part's readings equal
  to another group's, or a position's to the handout's example, after an offset -- and,
  when the readings take many values, after reordering.
* **too close to the truth**: |error| far below its σ (|z| < 0.0025 has probability 0.2 %
  for an honest result).
* **times** (readings sent with their times: a file, the API, the bridge): a gyro's clock
  only runs forward, so a reading timed at or before the one before it was not recorded
  in that order; and the readings' median time step is the gyro's sample interval 1/f --
  a step more than 5 % off says the readings came from another instrument or setting, or
  were timed by hand.

The thresholds are set so that honest simulated classes are flagged at most 1 % of the
time; bench/bench_evidence.py measures the false-alarm and detection rates.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from app.core.data_copies import copy_keys, handout_matches, typed_step
from app.core.noise_model import GyroNoise
from app.core.reading_moments import expected_variance, reading_moments, readings_rate_hz

SCATTER_P = 1e-5  # two-sided tail of χ²_ν for the scatter check
SMOOTH_SIGMAS = 4.0  # r₁ − ρ₁ above this many 1/√N
DIGITS_P = 1e-4
DIGITS_MIN_READINGS = 40
DIGITS_MIN_STEPS = 3.0  # the scatter spans at least this many typed steps
TRUTH_Z = 0.0025
OFF_GRID_SHARE = 0.2  # honest readings of a simulated gyro are all on its grid
TIME_STEP_TOLERANCE = 0.05  # the median time step against the gyro's 1/f


@dataclass(frozen=True)
class Evidence:
    """One finding: what it is (a message key's last part), where, and its numbers."""

    # scatter_low | scatter_high | smooth | digits | off_grid | copy | handout | too_close |
    # time_order | time_step
    check: str
    part: str
    numbers: dict = field(default_factory=dict)

    def to_json(self) -> dict:
        return {"check": self.check, "part": self.part, **self.numbers}


# --- the checks -------------------------------------------------------------------------


@lru_cache(maxsize=4096)
def _scatter_bounds(dof: int) -> tuple[float, float]:
    """χ²_ν's central 1 − 10⁻⁵ interval for ν = ``dof`` (``scatter_and_smoothness``; a
    class's parts share a few ν, and each pair of quantiles costs ≈ 0.1 ms)."""
    from scipy.stats import chi2

    return float(chi2.ppf(SCATTER_P / 2, dof)), float(chi2.ppf(1 - SCATTER_P / 2, dof))


def scatter_and_smoothness(
    part: str, positions: Sequence[np.ndarray], noise: GyroNoise, rate_hz: float
) -> list[Evidence]:
    """The scatter and lag-1 checks of one part's positions (module docstring).

    Parameters
    ----------
    part : str
        "heading" or "latitude".
    positions : sequence of numpy.ndarray
        Each position's readings (°/h).
    noise : GyroNoise
        The station's gyro.
    rate_hz : float
        Its readings per second.

    Returns
    -------
    list of Evidence
        ``scatter_low``/``scatter_high`` when ν·s²/E[s²] is outside χ²_ν's central
        1 − 10⁻⁵, ``smooth`` when r₁ − ρ₁ > 4/√N.
    """
    usable = [np.asarray(v, float) for v in positions if np.asarray(v).size >= 3]
    if not usable:
        return []
    found = []
    dof = sum(v.size - 1 for v in usable)
    centred = [v - v.mean() for v in usable]
    observed = sum(float(np.sum(c**2)) for c in centred)  # Σ (n − 1)·s²
    expected = sum(
        (v.size - 1) * expected_variance(noise, rate_hz, v.size, typed_step(v)) for v in usable
    )
    if expected > 0:
        statistic = dof * observed / expected
        ratio = math.sqrt(observed / expected)
        low, high = _scatter_bounds(dof)
        numbers = {
            "ratio": round(ratio, 3),
            "low": round(math.sqrt(low / dof), 3),
            "high": round(math.sqrt(high / dof), 3),
            "readings": dof + len(usable),
        }
        if statistic < low:
            found.append(Evidence("scatter_low", part, numbers))
        elif statistic > high:
            found.append(Evidence("scatter_high", part, numbers))
    pairs = sum(c.size - 1 for c in centred)
    if observed > 0 and pairs >= 20:
        r1 = sum(float(np.dot(c[:-1], c[1:])) for c in centred) / observed
        rho = float(np.mean([reading_moments(noise, rate_hz, v.size)[1] for v in usable]))
        if r1 - rho > SMOOTH_SIGMAS / math.sqrt(pairs):
            found.append(
                Evidence(
                    "smooth",
                    part,
                    {"r1": round(r1, 3), "expected": round(rho, 3), "pairs": pairs},
                )
            )
    return found


def last_digits(
    part: str, positions: Sequence[np.ndarray], noise_sd: float, own_step: float = 0.0
) -> list[Evidence]:
    """Pearson's χ² of the last typed digit against uniform (typed readings only).

    Parameters
    ----------
    part : str
        "heading" or "latitude".
    positions : sequence of numpy.ndarray
        Each position's readings (°/h).
    noise_sd : float
        The readings' expected standard deviation (°/h).
    own_step : float
        The gyro's own output step (°/h); 0 for none.

    Returns
    -------
    list of Evidence
        ``digits`` (with each digit's count) when p < 10⁻⁴ with 9 degrees of freedom;
        nothing tested under 40 readings, when the scatter spans fewer than 3 typed steps,
        or when the gyro's own step is coarser than the typed one (its readings then sit
        on its own grid).
    """
    from scipy.stats import chi2

    values = np.concatenate([np.asarray(v, float) for v in positions])
    step = typed_step(values)
    if (
        step is None
        or values.size < DIGITS_MIN_READINGS
        or noise_sd < DIGITS_MIN_STEPS * step
        or own_step > 0.5 * step
    ):
        return []
    digits = np.abs(np.round(values / step)).astype(np.int64) % 10
    counts = np.bincount(digits, minlength=10)
    expected = values.size / 10.0
    statistic = float(np.sum((counts - expected) ** 2) / expected)
    p = float(chi2.sf(statistic, 9))
    if p < DIGITS_P:
        top = int(np.argmax(counts))
        return [
            Evidence(
                "digits",
                part,
                {
                    "digit": top,
                    "share": round(counts[top] / values.size, 3),
                    "p": p,
                    "counts": counts.tolist(),
                },
            )
        ]
    return []


def off_grid(part: str, positions: Sequence[np.ndarray], own_step: float) -> list[Evidence]:
    """Readings between the simulated gyro's output steps.

    Parameters
    ----------
    part : str
        "heading" or "latitude".
    positions : sequence of numpy.ndarray
        Each position's readings (°/h).
    own_step : float
        The simulated gyro's output step q = 3600·lsb·f (°/h): its angle pulses over one
        sample, so every reading it shows is a whole multiple of q.

    Returns
    -------
    list of Evidence
        ``off_grid`` when more than 20 % of the readings lie more than half a typed step
        from every multiple of q (tested only when q is at least twice the typed step).
    """
    values = np.concatenate([np.asarray(v, float) for v in positions])
    step = typed_step(values) or 0.0
    if values.size == 0 or own_step <= 0 or own_step < 2.0 * step:
        return []
    distance = np.abs(values / own_step - np.round(values / own_step)) * own_step
    share = float(np.mean(distance > step / 2.0 + 1e-6 * own_step))
    if share > OFF_GRID_SHARE:
        return [Evidence("off_grid", part, {"share": round(share, 3), "step": own_step})]
    return []


def recording_times(
    part: str, times: Sequence[np.ndarray | None], rate_hz: float
) -> list[Evidence]:
    """Readings whose times do not fit how the gyro records: out of order, or at a step
    other than its sample interval.

    Parameters
    ----------
    part : str
        "heading" or "latitude".
    times : sequence of numpy.ndarray or None
        Each position's reading times (s), None where the readings came without times.
    rate_hz : float
        The station's gyro's readings per second, f.

    Returns
    -------
    list of Evidence
        ``time_order`` when some Δtᵢ ≤ 0 (with how many); ``time_step`` when the median of
        the positions' median steps, T̂, differs from 1/f by more than 5 %:
        |T̂·f − 1| > 0.05.  Positions without times, or with fewer than 3, are left out.
    """
    steps = [np.diff(np.asarray(t, float)) for t in times if t is not None and len(t) >= 3]
    if not steps:
        return []
    found = []
    backwards = sum(int(np.count_nonzero(d <= 0)) for d in steps)
    if backwards:
        found.append(Evidence("time_order", part, {"n": backwards}))
    typical = float(np.median([np.median(d) for d in steps]))
    if rate_hz > 0 and typical > 0 and abs(typical * rate_hz - 1.0) > TIME_STEP_TOLERANCE:
        found.append(
            Evidence("time_step", part, {"step": round(typical, 6), "expected": 1.0 / rate_hz})
        )
    return found


def too_close(part: str, error: float | None, sigma: float | None) -> list[Evidence]:
    """A result far closer to the truth than its own σ allows.

    Parameters
    ----------
    part : str
        "heading" or "latitude".
    error : float or None
        The result's error against the truth.
    sigma : float or None
        Its 1σ, same unit.

    Returns
    -------
    list of Evidence
        ``too_close`` when |z| = |error|/σ < 0.0025, which an honest result does with
        probability 0.2 % (normal errors).
    """
    if error is None or sigma is None or not sigma > 0 or not math.isfinite(error):
        return []
    z = abs(error) / sigma
    if z < TRUTH_Z:
        return [Evidence("too_close", part, {"z": round(z, 4), "sigma": sigma})]
    return []


# --- a part, and a class ----------------------------------------------------------------


def part_evidence(
    part: str,
    positions: Sequence[np.ndarray],
    typed: bool,
    noise: GyroNoise,
    rate_hz: float,
    *,
    simulated: bool = False,
    times: Sequence[np.ndarray | None] | None = None,
) -> list[Evidence]:
    """Every check of one part that needs only its own readings.

    Parameters
    ----------
    part : str
        "heading" or "latitude".
    positions : sequence of numpy.ndarray
        The positions' readings (°/h), in order.
    typed : bool
        Whether they were typed (the last-digit check).
    noise : GyroNoise
        The station's gyro.
    rate_hz : float
        Its readings per second.
    simulated : bool
        The station's gyro is the simulated one, whose output grid is known.
    times : sequence of numpy.ndarray or None, optional
        Each position's reading times (s) where they came with the readings.

    Returns
    -------
    list of Evidence
        Scatter and smoothness (judged at the readings' own rate where their times are
        faster than the gyro's: :func:`readings_rate_hz`), the output grid, last digits,
        the handout's tables, the recording times.
    """
    positions = [np.asarray(v, float) for v in positions]
    found = scatter_and_smoothness(part, positions, noise, readings_rate_hz(times, rate_hz))
    if simulated:
        found += off_grid(part, positions, 3600.0 * noise.angle_lsb_deg * rate_hz)
    if typed and positions:
        counts = [v.size for v in positions if v.size >= 2]
        if counts:
            step = typed_step(np.concatenate(positions))
            sd = math.sqrt(expected_variance(noise, rate_hz, int(np.median(counts)), step))
            found += last_digits(part, positions, sd, 3600.0 * noise.angle_lsb_deg * rate_hz)
    matches = handout_matches(positions)
    if matches:
        found.append(Evidence("handout", part, {"columns": matches}))
    if times is not None:
        found += recording_times(part, times, rate_hz)
    return found


def class_copies(
    takes: Sequence[tuple[str, str, Sequence[np.ndarray]]],
) -> dict[str, list[Evidence]]:
    """Parts of different groups whose readings match after an offset per position (or,
    where every position takes many values, after reordering within positions too).

    Parameters
    ----------
    takes : sequence of (group, part, positions)
        Every part of the class (and of earlier attempts or years, under their own group
        names), its positions' readings in order.

    Returns
    -------
    dict
        group → one "copy" finding per part, naming the other groups it matches.
    """
    owners: dict[str, set[str]] = {}
    keyed = [(group, part, copy_keys(positions)) for group, part, positions in takes]
    for group, _part, keys in keyed:
        for key in keys:
            owners.setdefault(key, set()).add(group)
    found: dict[str, dict[str, set[str]]] = {}
    for group, part, keys in keyed:
        for key in keys:
            others = owners[key] - {group}
            if others:
                found.setdefault(group, {}).setdefault(part, set()).update(others)
    return {
        group: [Evidence("copy", part, {"others": sorted(o)}) for part, o in sorted(parts.items())]
        for group, parts in found.items()
    }
