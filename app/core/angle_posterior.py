"""The 1σ of a direction when the amplitude is known: exact at any signal-to-noise.

The heading (or latitude) is the direction of a measured vector v̂ = (x, y) ~ N(H·u(θ), Σ)
whose length H is known in advance -- Ω·cos φ for the heading at a known station,
Ω for the latitude -- and whose direction θ is the unknown.  With every direction equally
likely beforehand the posterior of θ is

    p(θ | v̂) ∝ exp(H·uᵀΣ⁻¹v̂ − ½H²·uᵀΣ⁻¹u),   u = (cos θ, sin θ)

(for Σ = σ²I a von Mises distribution with κ = Ĥ·H/σ²).  The half-width of the interval
around the measured direction that holds 68.27 % of it is the honest 1σ at any
signal-to-noise ratio, also among the runs that pass the 3σ significance test: near that
limit the linear σ = σ/H covers only ≈ 58 % of them (the runs that pass are those whose
noise happened to lengthen the vector).  At high signal-to-noise it equals the linear σ.
"""

from __future__ import annotations

import math

import numpy as np

ONE_SIGMA = 0.6826894921370859
GRID = 4001  # points over ±12 linear σ (or the whole circle)
CONSISTENT = 5.0  # |Ĥ − H| beyond this many σ_H: the "known" amplitude does not fit the data


def angle_half_width(
    x: float, y: float, cov_xy: np.ndarray, amplitude: float, amplitude_sigma: float
) -> float | None:
    """68.27 % half-width (°) of the direction posterior around atan2(y, x).

    Parameters
    ----------
    x, y : float
        The measured vector (°/h).
    cov_xy : numpy.ndarray
        Its 2×2 covariance ((°/h)²).
    amplitude : float
        The known length H (°/h).
    amplitude_sigma : float
        σ of the measured length (°/h), to check that H fits the data.

    Returns
    -------
    float or None
        The half-width (°); None when H is unusable (not positive, or the measured length
        lies more than 5σ from it: a wrong unit, latitude or position) or Σ is singular.

    References
    ----------
    Mardia & Jupp, *Directional Statistics* (2000), §3.5 (von Mises) and §12 (Bayesian
    inference on the circle).
    """
    measured = math.hypot(x, y)
    if not (amplitude > 0 and math.isfinite(amplitude)) or not amplitude_sigma > 0:
        return None
    if abs(measured - amplitude) > CONSISTENT * amplitude_sigma:
        return None
    try:
        precision = np.linalg.inv(np.asarray(cov_xy, dtype=float))
    except np.linalg.LinAlgError:
        return None
    centre = math.atan2(y, x)
    linear = math.sqrt(float(np.max(np.linalg.eigvalsh(cov_xy)))) / max(measured, 1e-300)
    span = min(math.pi, 12.0 * linear)
    offsets = np.linspace(-span, span, GRID, endpoint=span < math.pi)
    u = np.stack([np.cos(centre + offsets), np.sin(centre + offsets)])
    v = np.array([x, y])
    log_p = amplitude * (v @ precision @ u) - 0.5 * amplitude**2 * np.einsum(
        "ik,ij,jk->k", u, precision, u
    )
    p = np.exp(log_p - log_p.max())
    p /= p.sum()
    order = np.argsort(np.abs(offsets), kind="stable")
    mass = np.cumsum(p[order])
    index = int(np.searchsorted(mass, ONE_SIGMA))
    return math.degrees(abs(offsets[order][min(index, offsets.size - 1)]))
