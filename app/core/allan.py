"""Allan deviation of a static rate record and the IEEE Std 952 terms it carries.

σ²(τ) = 3Q²/τ² + N²/τ + (2 ln2/π)·B² + K²·τ/3 + R²·τ²/2   (IEEE Std 952-1997, annex C).

The curve: ``allantools.oadev`` (overlapping, octave-spaced τ), with each σ̂²(τ)'s
equivalent degrees of freedom (Greenhall & Riley 2003, ``allantools.edf_greenhall``, for
the noise type that dominates at that τ) and its 68 % χ² confidence band.  The terms:
:func:`app.core.allan_fit.fit_terms` -- a log-domain fit weighted by those degrees of
freedom, every term ≥ 0, and a term reported only where the curve carries it, otherwise
"not resolved" with the upper bound the curve allows (lab-reference §6).

The dwell to recommend (lab-reference §6): the dwell per position that minimises the
four-position heading σ of the fitted model, inside the record's τ range
(:func:`app.core.dwell_advice.recommended_dwell`); from the curve's minimum where no model
fits; a lower bound where σ still falls at the longest τ.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from app.core.allan_curve import (
    allan_curve,
    allan_minimum,
    degrees_of_freedom,
    dominant_alphas,
    readable_points,
)
from app.core.allan_fit import MIN_REGION_EDF, TermEstimate, fit_terms
from app.core.angle_outputs import rates_from_angles
from app.core.dwell_advice import DwellAdvice, curve_dwell, recommended_dwell
from app.core.exceptions import UserError
from app.core.flicker import DEFAULT_BAND_S
from app.core.noise_model import GyroNoise
from app.core.record_preparation import prepare_record
from app.core.static_record import Progress, StaticRecord
from app.core.units import MAX_RATE_DEG_H

MIN_SAMPLES = 16
UNITS = {
    "quantization": "°",
    "arw": "°/√h",
    "bias_instability": "°/h",
    "rrw": "°/h/√h",
    "rate_ramp": "°/h²",
    "markov": "°/h",
    "sinusoid": "°/h",
}


@dataclass(frozen=True)
class AllanResult:
    taus_s: np.ndarray
    adev_deg_h: np.ndarray
    band_low_deg_h: np.ndarray
    band_high_deg_h: np.ndarray
    edf: np.ndarray
    model_adev_deg_h: np.ndarray
    terms: dict[str, TermEstimate]
    model_fits: bool
    tau_min_s: float
    adev_min_deg_h: float
    dwell: DwellAdvice
    rate_hz: float
    samples: int
    notes: list[dict] = field(default_factory=list)  # what was done to the record
    # each power-law term in the fit with every term free, resolved or not (°, °/√h …)
    fitted: dict[str, float] = field(default_factory=dict)

    def value(self, name: str) -> float | None:
        return self.terms[name].value

    @property
    def arw_deg_rt_h(self) -> float | None:
        return self.value("arw")

    @property
    def bias_instability_deg_h(self) -> float | None:
        return self.value("bias_instability")

    @property
    def rrw_deg_h_rt_h(self) -> float | None:
        return self.value("rrw")

    @property
    def quantization_deg(self) -> float:
        return self.value("quantization") or 0.0

    @property
    def recommended_dwell_s(self) -> float:
        return self.dwell.recommended_s

    @property
    def adev_error_deg_h(self) -> np.ndarray:
        """Half the width of the 68 % band at each τ (°/h), for error bars."""
        return (self.band_high_deg_h - self.band_low_deg_h) / 2.0

    def noise(self) -> GyroNoise:
        """The resolved terms as a noise model (unresolved terms left out)."""
        markov, sine = self.terms["markov"], self.terms["sinusoid"]
        band = (
            min(DEFAULT_BAND_S[0], float(self.taus_s[0])),
            max(DEFAULT_BAND_S[1], 10.0 * float(self.taus_s[-1])),
        )
        return GyroNoise(
            arw_deg_rt_h=self.arw_deg_rt_h or 0.0,
            bias_instability_deg_h=self.bias_instability_deg_h or 0.0,
            rrw_deg_h_rt_h=self.rrw_deg_h_rt_h or 0.0,
            angle_lsb_deg=self.quantization_deg * math.sqrt(12.0),
            flicker_band_s=band,
            markov_sigma_deg_h=markov.value or 0.0,
            markov_corr_time_s=markov.corr_time_s or 0.0,
            sine_amplitude_deg_h=sine.value or 0.0,
            sine_period_s=sine.period_s or 0.0,
            ramp_deg_h_per_h=self.value("rate_ramp") or 0.0,
        )

    def model_noise(self) -> GyroNoise:
        """The noise model the dwell advice follows: the resolved terms (:meth:`noise`), or
        where the curve holds more than they do, the fitted curve's terms as a whole
        (``dwell.source`` "fit") -- the model whose σ the results should carry."""
        noise = self.noise()
        return _fitted_noise(noise, self.fitted) if self.dwell.source == "fit" else noise

    def to_json(self) -> dict:
        return {
            "rate_hz": self.rate_hz,
            "samples": self.samples,
            "taus_s": self.taus_s.tolist(),
            "adev_deg_h": self.adev_deg_h.tolist(),
            "band_low_deg_h": self.band_low_deg_h.tolist(),
            "band_high_deg_h": self.band_high_deg_h.tolist(),
            "edf": self.edf.tolist(),
            "model_adev_deg_h": self.model_adev_deg_h.tolist(),
            "model_fits": self.model_fits,
            "terms": {name: term.to_json() for name, term in self.terms.items()},
            "units": UNITS,
            "arw_deg_rt_h": self.arw_deg_rt_h,
            "bias_instability_deg_h": self.bias_instability_deg_h,
            "rrw_deg_h_rt_h": self.rrw_deg_h_rt_h,
            "quantization_deg": self.quantization_deg,
            "tau_min_s": self.tau_min_s,
            "adev_min_deg_h": self.adev_min_deg_h,
            "recommended_dwell_s": self.dwell.recommended_s,
            "dwell": self.dwell.to_json(),
            "notes": self.notes,
        }


def _check_range(rates_deg_h: np.ndarray) -> None:
    """Refuse non-finite rates, and rates beyond ``MAX_RATE_DEG_H`` (no gyro's; the
    variances' squares would overflow)."""
    if not np.all(np.abs(rates_deg_h) <= MAX_RATE_DEG_H):
        if not np.all(np.isfinite(rates_deg_h)):
            raise UserError("readings.not_finite")
        raise UserError("readings.out_of_range")


def allan_deviation(
    rates_deg_h,
    rate_hz: float,
    *,
    notes: list[dict] | None = None,
    max_tau_s: float | None = None,
) -> AllanResult:
    """Overlapping Allan deviation (octave τ) of a rate record, with the terms it carries.

    Parameters
    ----------
    rates_deg_h : array_like
        The rate record (°/h), equally spaced.
    rate_hz : float
        The sample rate (Hz).
    notes : list of dict, optional
        What was done to the record before (trimmed, spikes, gaps), carried into the result.
    max_tau_s : float, optional
        The longest τ to analyse (s).

    Returns
    -------
    AllanResult
        τ (s), σ(τ) (°/h) with its degrees of freedom and 68 % band, every IEEE 952 term
        resolved or bounded, the model curve and the dwell advice.

    Raises
    ------
    UserError
        Too short a record, a non-positive rate, non-finite readings, or a constant record.

    References
    ----------
    IEEE Std 952-1997, annex C; allantools ``oadev``; NIST SP 1065 (2008);
    lab-reference §6.
    """
    data = np.asarray(rates_deg_h, dtype=float).ravel()
    if data.size < MIN_SAMPLES:
        raise UserError(
            "allan.too_short",
            minimum=MIN_SAMPLES,
        )
    _check_range(data)
    if not (rate_hz > 0 and math.isfinite(rate_hz)):
        raise UserError("allan.bad_rate")
    taus, adev = allan_curve(data, rate_hz)
    if max_tau_s is not None:
        keep = taus <= max_tau_s * (1 + 1e-9)
        taus, adev = taus[keep], adev[keep]
    if taus.size == 0:
        raise UserError(
            "allan.constant",
        )
    edf = degrees_of_freedom(taus, rate_hz, data.size, np.zeros(taus.size))
    fit = fit_terms(taus, adev, edf)
    alphas = dominant_alphas(taus, fit)
    edf = degrees_of_freedom(taus, rate_hz, data.size, alphas)
    fit = fit_terms(taus, adev, edf, alphas)
    modelled = fit.fits and any(t.resolved for t in fit.terms.values())
    readable = readable_points(edf)
    tau_min, adev_min = allan_minimum(taus, adev, edf, fit.model_adev if modelled else None)
    result = AllanResult(
        taus,
        adev,
        fit.band[0],
        fit.band[1],
        edf,
        fit.model_adev,
        fit.terms,
        fit.fits,
        tau_min,
        adev_min,
        curve_dwell(taus[readable], adev[readable]),
        float(rate_hz),
        int(data.size),
        list(notes or []),
        dict(fit.fitted),
    )
    if modelled:
        noise, source = result.noise(), "model"
        if fit.fits and _holds_more_than(noise, taus[readable], adev[readable],
                                         fit.band[0][readable], edf[readable]):  # fmt: skip
            noise, source = _fitted_noise(noise, fit.fitted), "fit"
        advice = recommended_dwell(noise, rate_hz, (float(taus[0]), float(taus[-1])), "record")
        result = _with_dwell(result, replace(advice, source=source))
    return result


MISSING_SHARE = 0.2  # the share of the curve's variance the resolved terms may leave out


def _holds_more_than(
    noise: GyroNoise, taus: np.ndarray, adev: np.ndarray, low: np.ndarray, edf: np.ndarray
) -> bool:
    """Whether the curve holds noise the resolved terms leave out: their σ²(τ) lies under the
    curve's 68 % band, short of the curve by a fifth of its variance or more, over τ's
    holding at least ``MIN_REGION_EDF`` degrees of freedom (a flicker floor and a random
    walk together that the curve carries but neither alone: the resolved angle random walk
    alone keeps falling where the curve has levelled off).  A resolved model a hair under
    a band made narrow by 10⁵ degrees of freedom leaves out nothing that moves the dwell."""
    resolved = noise.allan_variance(taus)
    short = (np.sqrt(resolved) < low) & (resolved < (1.0 - MISSING_SHARE) * adev**2)
    return bool(np.sum(edf[short]) >= MIN_REGION_EDF)


def _fitted_noise(noise: GyroNoise, fitted: dict[str, float]) -> GyroNoise:
    """The noise model of the fitted curve as a whole: each power-law term at its value in
    the fit with every term free, resolved or not (the resolved bumps kept)."""
    return replace(
        noise,
        arw_deg_rt_h=fitted.get("arw", 0.0),
        bias_instability_deg_h=fitted.get("bias_instability", 0.0),
        rrw_deg_h_rt_h=fitted.get("rrw", 0.0),
        angle_lsb_deg=fitted.get("quantization", 0.0) * math.sqrt(12.0),
        ramp_deg_h_per_h=fitted.get("rate_ramp", 0.0),
    )


def _with_dwell(result: AllanResult, advice: DwellAdvice) -> AllanResult:
    return replace(result, dwell=advice)


def analyse_record(
    record: StaticRecord,
    rate_hz: float | None,
    *,
    unit: str | None = None,
    max_tau_s: float | None = None,
    progress: Progress | None = None,
) -> AllanResult:
    """A real static record from reading to terms: unit, gaps, spikes, warm-up
    (:func:`app.core.record_preparation.prepare_record`), then :func:`allan_deviation`.

    Parameters
    ----------
    record : StaticRecord
        The record as read.
    rate_hz : float or None
        Sample rate (Hz); None: from the record's times.
    unit : str, optional
        The readings' unit (:data:`app.core.units.UNITS`); None: the unit the record's
        header names, else °/h.
    max_tau_s : float, optional
        The longest τ asked for (s).
    progress : callable, optional
        Told of each stage: ``progress(stage, details)``.

    Returns
    -------
    AllanResult
        With ``notes`` saying how the record was read and what was done to it.

    Raises
    ------
    UserError
        ``allan.unit_conflict`` when ``unit`` is not the unit the header names.

    References
    ----------
    IEEE Std 952-1997, annex C; lab-reference §6.
    """
    from app.core.units import (
        DEG_PER_HOUR,
        UNIT_SYMBOLS,
        canonical_unit,
        to_deg_per_hour,
        unit_doubt,
    )

    notes = list(record.notes)
    if rate_hz is None and record.times_s is None and record.stated_rate_hz:
        rate_hz = record.stated_rate_hz  # no times, no rate given: the one the file states
        stated = {"key": "allan.note_rate_stated", "params": {"rate": f"{rate_hz:g}"}}
        notes.append(record.rate_note or stated)
    chosen = canonical_unit(unit) if unit else None
    if record.angle is not None:  # angles per output: rates from them, in °/h
        if chosen:
            raise UserError("allan.angle_not_rate", unit=record.angle.unit)
        record, angle_notes = rates_from_angles(record, record.angle, rate_hz)
        notes += angle_notes
    if chosen and record.unit and chosen != record.unit:
        raise UserError(
            "allan.unit_conflict", header=UNIT_SYMBOLS[record.unit], chosen=UNIT_SYMBOLS[chosen]
        )
    if record.unit and record.unit != DEG_PER_HOUR and not chosen:  # not the default
        notes.append(
            {"key": "allan.note_unit_from_header", "params": {"unit": UNIT_SYMBOLS[record.unit]}}
        )
    values = to_deg_per_hour(record.values, chosen or record.unit or DEG_PER_HOUR)
    _check_range(values[np.isfinite(values)])  # lost readings: mended or cut out below
    prepared = prepare_record(
        StaticRecord(values, record.times_s, record.temperatures_c), rate_hz, max_tau_s=max_tau_s
    )
    if progress:
        progress("analyse", {"samples": int(prepared.values.size)})
    result = allan_deviation(
        prepared.values, prepared.rate_hz, notes=notes + prepared.notes, max_tau_s=max_tau_s
    )
    doubt = unit_doubt(result.adev_min_deg_h)
    if doubt:
        result.notes.append(doubt)
    return result
