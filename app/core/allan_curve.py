"""The Allan curve of a rate record and what its points can bear.

The curve: ``allantools.oadev`` (overlapping, octave-spaced τ).  Each σ̂²(τ)'s equivalent
degrees of freedom: Greenhall & Riley 2003 (``allantools.edf_greenhall``) for the noise
type that dominates at that τ.  The Allan minimum: read where the curve can bear it --
off the fitted model, or off points holding at least ``MIN_READ_EDF`` degrees of freedom.
"""

from __future__ import annotations

import numpy as np

from app.core.allan_fit import TERM_ALPHA, TERM_ORDER, TermFit
from app.core.allan_log_fit import BASES

# the fewest degrees of freedom a point of the curve needs to be read as its minimum (or the
# best dwell): at ν = 3 the 68 % band is ×0.75 … ×1.8, at ν = 1 ×0.7 … ×4.6
MIN_READ_EDF = 3.0


def degrees_of_freedom(
    taus_s: np.ndarray, rate_hz: float, count: int, alphas: np.ndarray
) -> np.ndarray:
    """Equivalent degrees of freedom of each overlapping σ̂²(τ).

    Parameters
    ----------
    taus_s : numpy.ndarray
        Averaging times τ (s).
    rate_hz : float
        Sample rate (Hz).
    count : int
        Samples in the record.
    alphas : numpy.ndarray
        The power-law noise type α (S_y ∝ f^α) that dominates at each τ.

    Returns
    -------
    numpy.ndarray
        ν for each τ (≥ 1).

    References
    ----------
    Greenhall & Riley, "Uncertainty of stability variances based on finite differences",
    PTTI 2003; NIST SP 1065 (2008), §5.3; ``allantools.edf_greenhall``.
    """
    import allantools

    edf = []
    for tau, alpha in zip(taus_s, alphas, strict=True):
        m = max(1, int(round(tau * rate_hz)))
        try:
            nu = allantools.edf_greenhall(
                alpha=int(alpha), d=2, m=m, N=count + 1, overlapping=True, modified=False
            )
        except NotImplementedError:  # α = 2 at τ of two differences or fewer: ν ≈ 1
            nu = 1.0
        edf.append(nu)
    return np.maximum(np.asarray(edf, dtype=float), 1.0)


def dominant_alphas(taus_s: np.ndarray, fit: TermFit) -> np.ndarray:
    """The noise type of the resolved term that contributes most at each τ.

    Parameters
    ----------
    taus_s : numpy.ndarray
        Averaging times τ (s).
    fit : TermFit
        A first fit of the curve.

    Returns
    -------
    numpy.ndarray
        α (S_y ∝ f^α) at each τ: 2 quantisation, 0 white, −1 flicker, −2 random walk.
    """
    tau_h = taus_s / 3600.0
    contributions, alphas = [], []
    for name in TERM_ORDER:
        term = fit.terms[name]
        if term.resolved:
            contributions.append(term.value**2 * BASES[name](tau_h))
            alphas.append(TERM_ALPHA[name])
    if not contributions:
        return np.zeros(taus_s.size)
    return np.asarray(alphas)[np.argmax(np.vstack(contributions), axis=0)]


def allan_curve(data: np.ndarray, rate_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """Overlapping Allan deviation at octave τ (allantools), positive values only.

    Parameters
    ----------
    data : numpy.ndarray
        The rate record (°/h).
    rate_hz : float
        Sample rate (Hz).

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        τ (s) and σ(τ) (°/h).

    References
    ----------
    IEEE Std 952-1997, annex C; NIST SP 1065 (2008), §5.2.4 (overlapping ADEV).
    """
    import allantools

    taus, adev, _, _ = allantools.oadev(data, rate=rate_hz, data_type="freq", taus="octave")
    keep = adev > 0
    return np.asarray(taus[keep], dtype=float), np.asarray(adev[keep], dtype=float)


def readable_points(edf: np.ndarray) -> np.ndarray:
    """The curve's points that can be read alone: those holding at least ``MIN_READ_EDF``
    degrees of freedom (all of them when none does).

    Parameters
    ----------
    edf : numpy.ndarray
        Each point's equivalent degrees of freedom.

    Returns
    -------
    numpy.ndarray of bool
        A mask over the points.
    """
    readable = edf >= MIN_READ_EDF
    return readable if readable.any() else np.ones(edf.size, dtype=bool)


def allan_minimum(
    taus_s: np.ndarray, adev_deg_h: np.ndarray, edf: np.ndarray, model_adev: np.ndarray | None
) -> tuple[float, float]:
    """The Allan minimum: the smallest σ(τ) and its τ.

    Read off the fitted model where it fits and resolves a term, else off the curve's
    points holding at least ``MIN_READ_EDF`` degrees of freedom.  A record's last τ rests
    on one or two differences (ν ≈ 1, a 68 % band of ×0.7 … ×4.6) and the lowest of twenty
    points picks such a dip: an 8-hour flicker record's last point sat at 0.12× the floor
    the fit resolved, below 0.664·B -- which lab-reference §6 calls a fit gone wrong.

    Parameters
    ----------
    taus_s, adev_deg_h : numpy.ndarray
        The curve: τ (s) and σ(τ) (°/h).
    edf : numpy.ndarray
        Each point's equivalent degrees of freedom.
    model_adev : numpy.ndarray or None
        The fitted model at each τ (°/h), or None where no model describes the curve.

    Returns
    -------
    (float, float)
        τ (s) and σ (°/h) at the minimum.

    References
    ----------
    IEEE Std 952-1997, annex C; NIST SP 1065 (2008), §5.3; lab-reference §6.
    """
    if model_adev is not None:
        taus, values = taus_s, model_adev
    else:
        readable = readable_points(edf)
        taus, values = taus_s[readable], adev_deg_h[readable]
    smallest = int(np.argmin(values))
    return float(taus[smallest]), float(values[smallest])
