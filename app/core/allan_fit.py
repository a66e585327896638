"""The IEEE Std 952 terms that an Allan curve carries, and only those.

Model (IEEE Std 952-1997 annex C, IEEE Std 1554-2005; lab-reference §6), τ in hours:

    σ²(τ) = 3Q²/τ² + N²/τ + (2 ln2/π)·B² + K²·τ/3 + R²·τ²/2  [+ σ_m²·g(τ/T_m)]

quantisation Q (°), angle random walk N (°/√h), bias instability B (°/h) as the flicker
floor 0.664·B, rate random walk K (°/h/√h), rate ramp R (°/h²) and, only where the curve
shows its bump, a Gauss–Markov bias σ_m (°/h) with correlation time T_m, or a sinusoid
Ω0 (°/h) of period P, Ω0²·sin⁴(πτ/P)/(πτ/P)² (IEEE 952 C.9: a bias swinging with the
lab's air conditioning), whichever fits the better.

Fit: weighted least squares in the log domain with every coefficient c_k ≥ 0,

    χ² = Σ_i [log Σ_k c_k f_k(τ_i) − (log σ̂²_i − E log(χ²_ν/ν))]² / (ψ₁(ν_i/2) + ε²)

(the residuals decorrelated along τ, neighbouring octave estimates sharing samples:
``allan_log_fit.NEIGHBOUR_CORRELATION``), with ν_i the equivalent degrees of freedom of σ̂²(τ_i)
(Greenhall & Riley 2003, for the noise type that dominates there): σ̂² ~ σ²·χ²_ν/ν, so
log σ̂² has mean log σ² + ψ(ν/2) + log(2/ν) and variance ψ₁(ν/2) (ψ, ψ₁ the digamma and trigamma
functions) -- the long-τ points, averaged over few stretches of the record, weigh little
and their downward bias in the log is removed; ε = ``allan_log_fit.MODEL_ERROR`` allows
for the ideal terms' shapes not being exact (sampling, real floors).

A term is *resolved* only when the curve carries it (lab-reference §6): its own line
√(c_k f_k(τ)) comes within the curve's confidence band (3σ of each log σ̂²: with twenty
τ's, a line running along the curve leaves a 68 % band somewhere by chance) at some τ of
the data holding ≥ ``MIN_REGION_EDF`` degrees of freedom, never rises above the band's
upper edge, and leaving it out makes the fit worse
by Δχ² ≥ ``SIGNIFICANCE``: of every subset of terms that are all carried, the one with
the least χ² + 9·(terms) is the model, and a term in it is resolved only when no other
term in its place comes within Δχ² < 4 (so a flicker floor and a random walk cannot stand
in for each other).  The rest are reported "not resolved" with the upper bound the curve
allows: the largest value whose line stays under the band's upper edge at every τ.

The least squares itself, for one chosen set of terms: :mod:`app.core.allan_log_fit`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from itertools import combinations

import numpy as np

from app.core.allan_log_fit import BASES, LogFit, Solution
from app.core.flicker import GM_PEAK_TAU_PER_T, SINE_PEAK_TAU_PER_PERIOD

SIGNIFICANCE = 9.0  # Δχ² a term must earn: 3σ for one parameter
RIVAL_MARGIN = 4.0  # Δχ² by which a term must beat any other term in its place (2σ)
BAND_LEVEL = 0.6826894921370859  # the band drawn and reported with the curve
# The τ region that carries a term must hold this many degrees of freedom in all: the
# longest τ's (ν ≈ 1–5 each, and correlated, since overlapping stretches share samples)
# cannot carry a term alone -- a high last point would read as rate random walk.
MIN_REGION_EDF = 10.0
TERM_ORDER = ("quantization", "arw", "bias_instability", "rrw", "rate_ramp")
# the noise type each term is (α of S_y(f) ∝ f^α) for the degrees of freedom
TERM_ALPHA = {
    "quantization": 2,
    "arw": 0,
    "bias_instability": -1,
    "rrw": -2,
    "rate_ramp": -2,
    "markov": -2,
    "sinusoid": -2,
}
BUMPS = ("markov", "sinusoid")
# a swing's period is at most the longest τ / 4 (the record holds ≥ ~10 periods): on 24-hour
# records of the simulator's flicker (a sum of Gauss–Markov processes) a long-τ wander was
# taken for a 3.6-hour "swing" in 3 of 8 records
SWING_REPEATS = 4.0
# Δχ² a swing must earn: its period is sought over ~15 octaves, so the 3σ of one term
# (Δχ² 9, p 0.27 %) is asked of the best of ~15 tries, each with two parameters:
# e^(−Δχ²/2) ≤ 0.27 %/15 gives Δχ² ≈ 17 -- a 24-hour record's random-walk wander earned
# 10.4, a 20-minute swing of 0.05 °/h on a 0.02 °/h gyro 34-54
SWING_SIGNIFICANCE = 2.0 * SIGNIFICANCE


@dataclass(frozen=True)
class TermEstimate:
    """One IEEE 952 term: its value where resolved, else the bound the curve allows."""

    name: str
    value: float | None  # None: not resolved
    interval: tuple[float, float] | None = None  # 68 % interval of a resolved value
    upper_bound: float | None = None  # for an unresolved term
    tau_region_s: tuple[float, float] | None = None  # where its line meets the curve's band
    corr_time_s: float | None = None  # the Gauss–Markov bias only
    period_s: float | None = None  # the sinusoid only

    @property
    def resolved(self) -> bool:
        return self.value is not None

    def to_json(self) -> dict:
        return {
            "resolved": self.resolved,
            "value": self.value,
            "interval": None if self.interval is None else list(self.interval),
            "upper_bound": self.upper_bound,
            "tau_region_s": None if self.tau_region_s is None else list(self.tau_region_s),
            **({"corr_time_s": self.corr_time_s} if self.name == "markov" else {}),
            **({"period_s": self.period_s} if self.name == "sinusoid" else {}),
        }


@dataclass(frozen=True)
class TermFit:
    terms: dict[str, TermEstimate]
    chi2: float
    dof: int
    model_adev: np.ndarray  # the fitted model's σ(τ) at each τ (°/h)
    band: tuple[np.ndarray, np.ndarray]  # the curve's 68 % band (low, high) (°/h)
    edf: np.ndarray = field(repr=False, default_factory=lambda: np.empty(0))
    # each power-law term's value in the fit with every term free (the model curve's),
    # resolved or not: what the curve holds as a whole where no one term carries it alone
    fitted: dict[str, float] = field(default_factory=dict)

    @property
    def fits(self) -> bool:
        """The model describes the curve: χ² per degree of freedom below 4."""
        return self.dof <= 0 or self.chi2 / self.dof < 4.0


def curve_band(adev: np.ndarray, edf: np.ndarray, level: float = BAND_LEVEL):
    """The curve's confidence band: σ̂·√(ν/χ²_ν((1±p)/2)) at each τ.

    Parameters
    ----------
    adev : numpy.ndarray
        σ̂(τ) (°/h).
    edf : numpy.ndarray
        Equivalent degrees of freedom ν of each σ̂².
    level : float
        The band's coverage p (default 68.3 %).

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        The low and high edge (°/h).

    References
    ----------
    NIST SP 1065 (2008), §5.3 (chi-squared confidence intervals).
    """
    from scipy.stats import chi2

    low = adev * np.sqrt(edf / chi2.ppf(0.5 + level / 2, edf))
    high = adev * np.sqrt(edf / chi2.ppf(0.5 - level / 2, edf))
    return low, high


def _value(name: str, coefficient: float) -> float:
    return math.sqrt(max(coefficient, 0.0))


def fit_terms(
    taus_s: np.ndarray, adev: np.ndarray, edf: np.ndarray, alphas: np.ndarray | None = None
) -> TermFit:
    """The resolved IEEE 952 terms of an Allan curve, with intervals; bounds for the rest.

    Parameters
    ----------
    taus_s : numpy.ndarray
        Averaging times τ (s), increasing.
    adev : numpy.ndarray
        The overlapping Allan deviation σ̂(τ) (°/h).
    edf : numpy.ndarray
        Equivalent degrees of freedom of each σ̂²(τ).
    alphas : numpy.ndarray, optional
        The noise type dominating at each τ (for the correlation between τ's; default
        white).

    Returns
    -------
    TermFit
        Every term of ``TERM_ORDER`` and of ``BUMPS``: resolved with a value (Q in °,
        N °/√h, B °/h, K °/h/√h, R °/h², the Markov σ in °/h with its T in s, the
        sinusoid's Ω0 in °/h with its P in s), its 68 % interval and τ region, or not
        resolved with its upper bound; χ² and the model curve.

    References
    ----------
    IEEE Std 952-1997, annex C; IEEE Std 1554-2005; NIST SP 1065 (2008);
    lab-reference §6.
    """
    taus_s, adev, edf = (np.asarray(a, dtype=float) for a in (taus_s, adev, edf))
    edf = np.maximum(edf, 1.0)
    alphas = np.zeros(taus_s.size) if alphas is None else np.asarray(alphas)
    fitter = LogFit(taus_s, adev, edf, alphas)
    low, high = fitter.resolve_band()
    best = _resolve(fitter, list(TERM_ORDER), low, high)
    base = best
    if taus_s.size >= 6:
        # a bump: a Gauss–Markov bias or a periodic one, whichever fits the better
        markov = _try_bump(fitter, base, low, high, "markov")
        sinusoid = _try_bump(fitter, base, low, high, "sinusoid")
        if markov and (not sinusoid or markov[0].chi2 <= sinusoid[0].chi2):
            best, fitter.sine_period_h = markov, None
        elif sinusoid:
            best, fitter.markov_time_h = sinusoid, None
    resolved = [n for n in best[0].names if best[1].get(n)]
    # Values and intervals from the fit with every term free (≥ 0), where the term is still
    # carried there: a term present but too weak to resolve then takes its share instead of
    # biasing the resolved ones; else from the model that resolved it.
    solution = fitter.solve([*TERM_ORDER, *(b for b in BUMPS if b in resolved)])
    terms: dict[str, TermEstimate] = {}
    for name in (*TERM_ORDER, *BUMPS):
        if name in resolved:
            carried = _carried(fitter, solution, name, low, high)
            terms[name] = _resolved(fitter, solution if carried else best[0], name, low)
        elif name in BUMPS:
            terms[name] = TermEstimate(name, None)
        else:
            column = BASES[name](fitter.tau_h)
            bound = float(np.min(high**2 / column))
            terms[name] = TermEstimate(name, None, upper_bound=_value(name, bound))
    dof = int(taus_s.size - np.count_nonzero(solution.coefficients))
    band = curve_band(adev, edf)
    fitted = {
        name: _value(name, float(solution.coefficients[solution.names.index(name)]))
        for name in TERM_ORDER
    }
    return TermFit(terms, solution.chi2, dof, np.sqrt(solution.model), band, edf, fitted)


def _resolved(fitter: LogFit, solution: Solution, name: str, low: np.ndarray) -> TermEstimate:
    index = solution.names.index(name)
    c = float(solution.coefficients[index])
    line = np.sqrt(c * fitter.basis(name))
    region = _carrying_region(line >= low, fitter.edf, fitter.tau_h * 3600.0)
    interval = None
    if solution.cov is not None:
        sigma = math.sqrt(max(solution.cov[index, index], 0.0))
        interval = (_value(name, c - sigma), _value(name, c + sigma))
    corr = fitter.markov_time_h * 3600.0 if name == "markov" else None
    period = fitter.sine_period_h * 3600.0 if name == "sinusoid" else None
    return TermEstimate(name, _value(name, c), interval, None, region, corr, period)


def _carrying_region(
    inside: np.ndarray, edf: np.ndarray, taus_s: np.ndarray
) -> tuple[float, float] | None:
    """The τ region said to carry a term: of the runs of neighbouring τ where its line is
    inside the band, the one holding the most degrees of freedom -- not the span from the
    first such τ to the last, which would take in the τ's between, where the line can lie
    far below the curve (angle random walk "carried by τ = 0.2 … 13107 s" because the
    one-difference last τ's band reaches down to it)."""
    best, best_edf, start = None, 0.0, None
    for k, flag in enumerate([*inside.tolist(), False]):
        if flag and start is None:
            start = k
        elif not flag and start is not None:
            held = float(np.sum(edf[start:k]))
            if held > best_edf:
                best, best_edf = (float(taus_s[start]), float(taus_s[k - 1])), held
            start = None
    return best


def _carried(fitter, solution, name, low, high) -> bool:
    c = solution.coefficients[solution.names.index(name)]
    if c <= 0:
        return False
    line = np.sqrt(c * fitter.basis(name))
    inside = line >= low
    return bool(np.sum(fitter.edf[inside]) >= MIN_REGION_EDF and np.all(line <= high * (1 + 1e-9)))


def _resolve(fitter: LogFit, names: list[str], low, high):
    """The terms the curve carries.  Of every subset of ``names`` whose terms are all present
    (> 0) and carried (:func:`_carried`), the one with the least χ² + SIGNIFICANCE·(number of
    terms) is the model: each of its terms earns Δχ² ≥ 9 against leaving it out.  A term is
    resolved only if, besides, no other term in its place fits within Δχ² < 4
    (``RIVAL_MARGIN``) -- a floor that could as well be a random walk is neither.  Returns
    the model's solution and {term: True} for the resolved ones."""
    scores: dict[frozenset, float] = {}
    best = None
    for size in range(1, len(names) + 1):
        for subset in combinations(names, size):
            solution = fitter.solve(list(subset))
            if np.any(solution.coefficients <= 0):
                continue
            if not all(_carried(fitter, solution, n, low, high) for n in subset):
                continue
            score = solution.chi2 + SIGNIFICANCE * size
            scores[frozenset(subset)] = score
            if best is None or score < best[0]:
                best = (score, solution)
    if best is None:
        return fitter.solve(list(names)), {}
    score, solution = best
    chosen = frozenset(solution.names)
    status = {}
    for term in chosen:
        ambiguous = any(
            scores.get((chosen - {term}) | {other}, math.inf) < score + RIVAL_MARGIN
            for other in names
            if other not in chosen
        )
        status[term] = not ambiguous
    return solution, status


SHOULDER = 0.05  # the fall of the log-log slope that no sum of power laws can make


def _has_peak(model_variance: np.ndarray, taus_h: np.ndarray) -> bool:
    """The model curve rises and then falls inside the data (a local maximum)."""
    steps = np.diff(model_variance)
    rising = np.flatnonzero(steps > 0)
    return bool(rising.size and np.any(steps[rising[0] + 1 :] < 0))


def _has_bump(model_variance: np.ndarray, taus_h: np.ndarray) -> bool:
    """The model curve bends as no power laws can: a bump or a shoulder.

    A sum of power laws Σ c_k·τ^a_k is log-convex in log τ (its log-log slope never falls),
    so a slope that falls by more than ``SHOULDER`` between neighbouring τ's is a feature
    only a bump term makes -- a local maximum, or a shoulder on a falling curve (a swing
    under angle random walk).
    """
    slopes = np.diff(np.log(np.maximum(model_variance, 1e-300))) / np.diff(np.log(taus_h))
    return bool(np.any(np.diff(slopes) < -SHOULDER))


def _try_bump(fitter: LogFit, base, low, high, kind: str):
    """A bump term (``kind``: a Gauss–Markov bias or a sinusoid), only where the curve shows
    its bump: shape parameters whose peak lies inside the data (the Markov's at τ = 1.89·T,
    the sinusoid's at τ = 0.371·P), a model that rises and falls there (the Markov's,
    :func:`_has_peak`) or bends as power laws cannot (the sinusoid's, :func:`_has_bump`: a
    shoulder too), and a fit better by
    Δχ² ≥ SIGNIFICANCE than every power-law term together (a flicker floor, a random walk
    and a ramp are the default explanation); then resolved like every other term.  Leaves
    the shape found on ``fitter`` (``markov_time_h`` or ``sine_period_h``)."""
    solution, status = base
    resolved = [n for n in solution.names if status.get(n)]
    taus_h = fitter.tau_h
    if kind == "markov":  # among the terms resolved without it, at a local maximum
        searched, bends, refine = resolved, _has_peak, False
        grid = np.geomspace(taus_h[1] / GM_PEAK_TAU_PER_T, taus_h[-2] / GM_PEAK_TAU_PER_T, 24)
    else:
        # a swing hides the power laws it sits on (a fast one under angle random walk left
        # none resolved): its period is sought with all of them free, and a shoulder counts;
        # it must repeat ~10 times in the record -- a long-τ wander is no swing
        searched, bends, refine = list(TERM_ORDER), _has_bump, True
        resolved = resolved or list(TERM_ORDER)
        longest = min(taus_h[-2] / SINE_PEAK_TAU_PER_PERIOD, taus_h[-1] / SWING_REPEATS)
        grid = np.geomspace(taus_h[1] / SINE_PEAK_TAU_PER_PERIOD, longest, 48)
    attribute = "markov_time_h" if kind == "markov" else "sine_period_h"
    power_laws = fitter.solve(list(TERM_ORDER)).chi2
    needed = SIGNIFICANCE if kind == "markov" else SWING_SIGNIFICANCE
    if power_laws < needed:  # no term can lower χ² by more than all of it: nothing to seek
        return None
    best = None
    step = float(grid[1] / grid[0])
    for shapes in (grid, None):  # the grid, then (a swing's lobes) finer around its best
        if shapes is None:
            if not refine:
                break
            shapes = np.geomspace(best[1] / step, best[1] * step, 9)
        for shape in shapes:
            setattr(fitter, attribute, float(shape))
            trial = fitter.solve([*searched, kind])
            if best is None or trial.chi2 < best[0].chi2:
                best = (trial, float(shape))
    setattr(fitter, attribute, None)
    if best is None or power_laws - best[0].chi2 < needed:
        return None
    if not bends(best[0].model, taus_h):
        return None
    setattr(fitter, attribute, best[1])
    result = _resolve(fitter, [*resolved, kind], low, high)
    if kind not in result[0].names or not result[1].get(kind):
        setattr(fitter, attribute, None)
        return None
    return result
