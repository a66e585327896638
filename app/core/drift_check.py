"""Is the gyro's bias drifting through the run (a cold start)?

After switch-on a FOG's bias settles over minutes (lab-reference §6, warm-up).  Readings
taken then carry a bias that changes from position to position; four-position data move
the heading by ≈ Δb/H rad, far beyond the σ of the noise, and nothing in the position means
alone shows it.  Three witnesses, each a linear bias drift ḃ (°/h per hour; per reading
when the record has no times):

* the closure d = (m1 + m3 − m2 − m4)/2 of four positions 90° apart is pure noise for a
  steady bias (lab-reference §3), and d = ḃ·(t̄1 + t̄3 − t̄2 − t̄4)/2 for a drifting one:
  ḃ_c = d / ((t̄1 + t̄3 − t̄2 − t̄4)/2), σ from the closure's own σ_d;
* the trend within each position (the sinusoid is constant there): the pooled slope of
  block means against time, ḃ_w = ΣΣ(t − t̄_i)(m − m̄_i)/ΣΣ(t − t̄_i)², its σ from the
  blocks' scatter about each position's own line (Student-t: correlated noise shows there);
* the case temperature, where the record has one: a run over which it changes by more
  than 1 °C was taken during warm-up;
* the gyro's own noise model, where it is known with the time since switch-on (the
  simulated gyro, ``solve --gyro-preset`` with times): its warm-up b_w·e^(−t/τ_w) is part of
  the means' covariance, so the 1σ already covers it; a run whose σ² is at least
  ``MODEL_SHARE`` warm-up is flagged too ("model").

ḃ_c and ḃ_w are combined by inverse variance (a closure that the trends contradict by
more than 3σ is a wrong position or a bump, not a drift, and is left out), z = ḃ/σ_ḃ;
|z| ≥ ``FLAG_Z`` (or the temperature) flags the run.  The solver then estimates what the
drift did to the result -- each position mean corrected by ḃ·(t̄_i − t̄), solved again --
and widens the 1σ by that shift (added in quadrature), so a flagged result is both said
and covered.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from app.core.sinusoid import SinusoidFit, fit_sinusoid, wrap360

FLAG_Z = 3.0
MODEL_SHARE = 0.25
TEMPERATURE_LIMIT_C = 1.0
MAX_BLOCKS = 8
WAIT_MINUTES = 15  # a FOG's usual warm-up when the gyro's own is not known


@dataclass(frozen=True)
class DriftCheck:
    """The drift seen in a run, and whether it is flagged."""

    rate: float | None  # ḃ: °/h per hour (timed) or °/h per reading (untimed)
    sigma: float | None
    z: float | None
    flagged: bool
    timed: bool
    witnesses: tuple[str, ...]  # which of "closure", "trend", "temperature" saw it
    temperature_change_c: float | None = None
    shift: dict | None = None  # what the drift moved: {"azimuth_deg": …} or latitude, rate
    wait_minutes: int = WAIT_MINUTES
    warm_up_share: float | None = None  # the warm-up's share of the σ² (known noise model)

    def to_json(self) -> dict:
        return {
            "flagged": self.flagged,
            "drift_rate": self.rate,
            "drift_sigma": self.sigma,
            "drift_unit": "deg/h per h" if self.timed else "deg/h per reading",
            "z": self.z,
            "witnesses": list(self.witnesses),
            "temperature_change_c": self.temperature_change_c,
            "shift": self.shift,
            "wait_minutes": self.wait_minutes,
            "warm_up_share": self.warm_up_share,
        }


def _mean_times(
    arrays: list[np.ndarray], times_s: Sequence[Sequence[float]] | None
) -> tuple[list[np.ndarray], bool]:
    """Each reading's time in hours (timed), else its index in the run (back to back)."""
    if times_s is not None and len(times_s) == len(arrays):
        stamps = [np.asarray(t, dtype=float).ravel() for t in times_s]
        if all(
            s.size == a.size and np.all(np.isfinite(s)) for s, a in zip(stamps, arrays, strict=True)
        ):
            return [s / 3600.0 for s in stamps], True
    clock, out = 0, []
    for array in arrays:
        out.append(clock + np.arange(array.size, dtype=float))
        clock += array.size
    return out, False


def _closure_witness(
    means: np.ndarray, mean_times: np.ndarray, closure: float | None, closure_sigma: float | None
) -> tuple[float, float] | None:
    if closure is None or not closure_sigma or means.size != 4:
        return None
    lever = (mean_times[0] + mean_times[2] - mean_times[1] - mean_times[3]) / 2.0
    if abs(lever) <= 0:
        return None
    return closure / lever, closure_sigma / abs(lever)


def _trend_witness(arrays: list[np.ndarray], times: list[np.ndarray]) -> tuple[float, float] | None:
    """Pooled within-position slope of block means, with its Student-t σ (as a z-equivalent)."""
    # scipy.stats' t.sf(x, ν) and norm.isf(p) are these two special functions behind its
    # generic distribution machinery (which costs ≈ 0.1 ms a call; these ≈ 2 µs)
    from scipy.special import ndtri, stdtr

    sxy = sxx = residual = 0.0
    dof = 0
    for values, stamps in zip(arrays, times, strict=True):
        blocks = min(MAX_BLOCKS, values.size)
        if blocks < 3:
            continue
        edges = np.linspace(0, values.size, blocks + 1).astype(int)  # no empty block
        sizes = np.diff(edges)
        m = np.add.reduceat(values, edges[:-1]) / sizes
        t = np.add.reduceat(np.asarray(stamps, dtype=float), edges[:-1]) / sizes
        dt, dm = t - t.mean(), m - m.mean()
        if not np.any(dt):
            continue
        own = float(dt @ dm / (dt @ dt))
        residual += float(np.sum((dm - own * dt) ** 2))
        sxy += float(dt @ dm)
        sxx += float(dt @ dt)
        dof += blocks - 2
    if sxx <= 0 or dof < 2:
        return None
    slope = sxy / sxx
    scale = math.sqrt(residual / dof / sxx)
    if scale <= 0:
        return None
    # a t-distributed ratio as the normal σ with the same tail probability
    t_ratio = abs(slope) / scale
    z = -float(ndtri(stdtr(dof, -t_ratio))) if t_ratio > 0 else 0.0  # isf(sf(t_ratio))
    sigma = abs(slope) / z if z > 0 else scale
    return slope, float(sigma)


def check_drift(
    arrays: Sequence[np.ndarray],
    means: np.ndarray,
    closure: float | None,
    closure_sigma: float | None,
    *,
    times_s: Sequence[Sequence[float]] | None = None,
    temperatures_c: Sequence[Sequence[float]] | None = None,
    warm_up_share: float | None = None,
) -> DriftCheck:
    """Whether the run's bias drifted: the closure, the trends and the temperature.

    Parameters
    ----------
    arrays : sequence of numpy.ndarray
        Each position's readings (°/h), in recording order.
    means : numpy.ndarray
        The position means (°/h).
    closure, closure_sigma : float or None
        The closure d and its σ_d (°/h) when four positions lie 90° apart and σ_d comes from
        the readings or the noise model (not from d itself).
    times_s : sequence of sequences, optional
        Each reading's time (s, one clock).
    temperatures_c : sequence of sequences, optional
        Each reading's case temperature (°C).
    warm_up_share : float, optional
        The share of the result's variance that a known noise model gives the warm-up.

    Returns
    -------
    DriftCheck
        ḃ with its σ and z, whether flagged, and by which witness.

    References
    ----------
    lab-reference §3 (closure, drift during the sequence) and §6 (warm-up).
    """
    arrays = [np.asarray(a, dtype=float).ravel() for a in arrays]
    times, timed = _mean_times(arrays, times_s)
    mean_times = np.array([t.mean() for t in times])
    estimates, witnesses = [], []
    closure_part = _closure_witness(np.asarray(means), mean_times, closure, closure_sigma)
    trend_part = _trend_witness(arrays, times)
    if closure_part is not None and trend_part is not None:
        gap = abs(closure_part[0] - trend_part[0]) / math.hypot(closure_part[1], trend_part[1])
        if gap > FLAG_Z:  # the positions disagree, but not as a drift would: a wrong
            closure_part = None  # position or a bump (the closure flag's business)
    for name, part in (("closure", closure_part), ("trend", trend_part)):
        if part is not None and part[1] > 0 and math.isfinite(part[1]):
            estimates.append(part)
            if abs(part[0]) / part[1] >= FLAG_Z:
                witnesses.append(name)
    rate = sigma = z = None
    if estimates:
        weights = np.array([1.0 / s**2 for _, s in estimates])
        rate = float(
            np.sum([r * w for (r, _), w in zip(estimates, weights, strict=True)]) / weights.sum()
        )
        sigma = float(1.0 / math.sqrt(weights.sum()))
        z = rate / sigma
    change = None
    if temperatures_c:
        present = [np.asarray(t, dtype=float).ravel() for t in temperatures_c if t is not None]
        present = [t for t in present if t.size]
        if present:
            every = np.concatenate(present)
            change = float(every.max() - every.min())
            if change > TEMPERATURE_LIMIT_C:
                witnesses.append("temperature")
    if warm_up_share is not None and warm_up_share >= MODEL_SHARE:
        witnesses.append("model")
    flagged = bool(
        (z is not None and abs(z) >= FLAG_Z) or {"temperature", "model"} & set(witnesses)
    )
    if flagged and z is not None and abs(z) >= FLAG_Z and not witnesses:
        witnesses.append("combined")
    return DriftCheck(
        rate, sigma, z, flagged, timed, tuple(witnesses), change, warm_up_share=warm_up_share
    )


def position_offsets(check: DriftCheck, arrays, times_s) -> np.ndarray:
    """The bias each position mean carries from the drift, ḃ·(t̄_i − t̄).

    Parameters
    ----------
    check : DriftCheck
        The drift seen.
    arrays : sequence of array_like
        Each position's readings.
    times_s : sequence of sequences, optional
        Each reading's time (s); without, the readings' order.

    Returns
    -------
    numpy.ndarray
        The offset of each position mean (°/h).
    """
    times, _ = _mean_times([np.asarray(a, dtype=float).ravel() for a in arrays], times_s)
    mean_times = np.array([t.mean() for t in times])
    return (check.rate or 0.0) * (mean_times - mean_times.mean())


def warm_up_message(check: DriftCheck, wait_minutes: int | None = None) -> tuple[str, dict]:
    """The flag's message key and parameters, for every place that says it (the lab page,
    the review, the PDF, the CLI): how far the drift moved the result where it was
    corrected, else that the σ holds the modelled warm-up; how long to wait.

    Parameters
    ----------
    check : DriftCheck
        A flagged check.
    wait_minutes : int, optional
        Minutes until the gyro is warm, where known (0: warm by now).

    Returns
    -------
    (str, dict)
        The catalogue key and its parameters.
    """
    minutes = check.wait_minutes if wait_minutes is None else wait_minutes
    shift = check.shift or {}
    moved = next((abs(v) for k, v in shift.items() if k.endswith("_deg")), None)
    if moved is None:
        key = "flag.warming_up_model" if minutes else "flag.warming_up_model_waited"
        return key, {"minutes": minutes}
    key = "flag.warming_up" if minutes else "flag.warming_up_waited"
    return key, {"minutes": minutes, "moved": f"{moved:.2f}°"}


def drift_and_its_effect(
    positions, fit: SinusoidFit, times_s, temperatures_c, part: str, angles_deg, warm_up_cov
) -> tuple[DriftCheck | None, tuple[float, ...] | None]:
    """The warm-up check of a run solved without a fitted drift term and, where a seen
    drift is flagged, the result recomputed from means corrected by ḃ·(t̄_i − t̄).

    Parameters
    ----------
    positions : sequence of array_like
        Each position's readings (°/h).
    fit : SinusoidFit
        The run's fit (its closure, covariance and noise model).
    times_s, temperatures_c : sequences, optional
        Each reading's time (s) and case temperature (°C).
    part : {"heading", "latitude"}
        Which result to recompute.
    angles_deg : sequence of float
        The positions' angles (°).
    warm_up_cov : numpy.ndarray, optional
        The known noise model's warm-up share of the means' covariance.

    Returns
    -------
    (DriftCheck or None, tuple or None)
        The check (None when the fit has its own drift term) and the recomputed
        (azimuth,) or (latitude, Earth rate) -- None when nothing is to be corrected, or
        when the noise model's σ already holds the warm-up.

    References
    ----------
    lab-reference §3 (drift during the sequence) and §6 (warm-up).
    """
    if fit.drift is not None:  # five or more timed positions: the drift is in the fit already
        return None, None
    closure_sigma = fit.closure_sigma if fit.uncertainty_model != "closure" else None
    share = None
    if warm_up_cov is not None and fit.cov is not None:
        warm = fit_sinusoid(positions, angles_deg, position_cov=warm_up_cov).cov
        total = fit.cov[0, 0] + fit.cov[1, 1]
        share = float((warm[0, 0] + warm[1, 1]) / total) if total > 0 else None
    check = check_drift(
        [np.asarray(p, dtype=float) for p in positions],
        fit.means,
        fit.closure_residual,
        closure_sigma,
        times_s=times_s,
        temperatures_c=temperatures_c,
        warm_up_share=share,
    )
    seen = {"closure", "trend", "combined", "temperature"} & set(check.witnesses)
    if not check.flagged or check.rate is None or not seen or "model" in check.witnesses:
        return check, None  # nothing to correct, or the noise model's σ holds the warm-up
    offsets = position_offsets(check, positions, times_s)
    corrected = [np.asarray(p, dtype=float) - o for p, o in zip(positions, offsets, strict=True)]
    again = fit_sinusoid(corrected, angles_deg)
    if part == "heading":
        azimuth = math.degrees(math.atan2(-again.c, again.a)) + float(again.angles_deg[0])
        return check, (wrap360(azimuth),)
    return check, (math.degrees(math.atan2(again.c, again.a)), math.hypot(again.a, again.c))
