"""The weighted least squares under the Allan fit: log σ̂²(τ) against Σ c_k·f_k(τ), every
c_k ≥ 0, each point weighted by its χ² scatter ψ₁(ν/2) plus a model error, neighbouring
τ's decorrelated, and the coefficients' covariance by the sandwich M·Σ·Mᵀ
(:mod:`app.core.allan_fit` chooses the terms and says which are resolved).

The target is log σ̂² − (ψ(ν/2) + log(2/ν)), the unbiased log of a χ²_ν/ν-scaled variance
(IEEE Std 952-1997, annex C; NIST SP 1065 (2008), §5.3; lab-reference §6).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from app.core.flicker import FLOOR_FACTOR, gauss_markov_avar, sinusoid_avar

# The band a term's line is held to: 3σ of each log σ̂²(τ), σ including MODEL_ERROR.  A
# resolved term's line runs along the curve, and with ~20 τ's some point lies outside its own
# 68 % band by chance.
RESOLVE_SIGMAS = 3.0
# The IEEE model is an idealisation: a sampled record's first τ's differ from the
# continuous-time terms (a sampled random walk reads √1.5 × K·√(τ/3) at τ = Δt) and real
# floors are not perfectly flat.  Each log σ̂² is given this much model error (≈ 5 % in σ)
# on top of its statistical scatter, so the τ's with 10⁵ degrees of freedom do not steer
# the fit by their discretisation: ε(m) = MODEL_ERROR·(1 + 2/m) at τ = m·Δt (a sampled
# random walk or flicker reads 20 % high at m = 1, 6 % at m = 2, 1–2 % at m = 4).
MODEL_ERROR = 0.1
# Correlation of log σ̂² between neighbouring octave τ's (overlapping estimates share
# samples), by noise type; measured on 300 independent records each: white 0.51, flicker
# 0.66, random walk 0.87 (tests/noise_sources.py); quantisation taken as white.
NEIGHBOUR_CORRELATION = {2: 0.5, 0: 0.5, -1: 0.66, -2: 0.87}

Basis = Callable[[np.ndarray], np.ndarray]
BASES: dict[str, Basis] = {  # f_k(τ_h), so that σ² = Σ value_k²·f_k  ((°/h)², τ in hours)
    "quantization": lambda tau_h: 3.0 / tau_h**2,
    "arw": lambda tau_h: 1.0 / tau_h,
    "bias_instability": lambda tau_h: np.full_like(tau_h, FLOOR_FACTOR**2),
    "rrw": lambda tau_h: tau_h / 3.0,
    "rate_ramp": lambda tau_h: tau_h**2 / 2.0,
}


@dataclass
class Solution:
    names: list[str]
    coefficients: np.ndarray  # c_k = value_k² (markov: σ_m²; sinusoid: Ω0²)
    chi2: float
    model: np.ndarray  # σ² at each τ
    cov: np.ndarray | None


class LogFit:
    """Weighted non-negative least squares of log σ² for a chosen set of terms."""

    def __init__(
        self, taus_s: np.ndarray, adev: np.ndarray, edf: np.ndarray, alphas: np.ndarray
    ) -> None:
        from scipy.special import digamma, polygamma

        self.tau_h = taus_s / 3600.0
        self.variance = adev**2
        half = edf / 2.0
        self.target = np.log(self.variance) - (digamma(half) + np.log(1.0 / half))
        m = np.maximum(taus_s / taus_s[0], 1.0)
        model_error = MODEL_ERROR * (1.0 + 2.0 / m)
        self.weight = 1.0 / np.sqrt(polygamma(1, half) + model_error**2)
        self.stat_weight = 1.0 / np.sqrt(polygamma(1, half))  # for the intervals
        # the sampled τ's own misfit (a few %, falling as 1/m) counts in the intervals: the
        # terms' shapes are exact only for m ≫ 1
        self.sampling_error = MODEL_ERROR / m
        self.edf = edf
        self.markov_time_h: float | None = None
        self.sine_period_h: float | None = None
        rho = np.array([NEIGHBOUR_CORRELATION.get(int(a), 0.5) for a in alphas])
        # neighbours i, i+1 correlated by r_i = √(ρ_i ρ_(i+1)): a first-order Markov chain
        # along τ, whitened by e_i = (u_i − r_(i−1)·u_(i−1))/√(1 − r_(i−1)²)
        self.step_correlation = np.sqrt(rho[:-1] * rho[1:])

    def statistical_cov(self) -> np.ndarray:
        """Covariance of the log σ̂²'s: ψ₁(ν/2) each, neighbours correlated along τ, plus
        the sampled τ's misfit (independent)."""
        sd = 1.0 / self.stat_weight
        count = sd.size
        logs = np.concatenate([[0.0], np.cumsum(np.log(self.step_correlation))])
        corr = np.exp(-np.abs(logs[:, None] - logs[None, :]))
        corr[np.arange(count), np.arange(count)] = 1.0
        return corr * np.outer(sd, sd) + np.diag(self.sampling_error**2)

    def whiten(self, values: np.ndarray) -> np.ndarray:
        """Decorrelate normalised residuals (or Jacobian rows) along τ."""
        out = values.copy()
        r = self.step_correlation
        if values.ndim == 1:
            out[1:] = (values[1:] - r * values[:-1]) / np.sqrt(1.0 - r * r)
        else:
            out[1:] = (values[1:] - r[:, None] * values[:-1]) / np.sqrt(1.0 - r * r)[:, None]
        return out

    def resolve_band(self) -> tuple[np.ndarray, np.ndarray]:
        """σ at log σ² = target ± 3 standard deviations (°/h)."""
        spread = RESOLVE_SIGMAS / self.weight
        return np.exp((self.target - spread) / 2.0), np.exp((self.target + spread) / 2.0)

    def basis(self, name: str) -> np.ndarray:
        if name == "markov":
            return gauss_markov_avar(self.tau_h, self.markov_time_h)
        if name == "sinusoid":
            return sinusoid_avar(self.tau_h, self.sine_period_h)
        return BASES[name](self.tau_h)

    def solve(self, names: list[str]) -> Solution:
        from scipy.optimize import least_squares, nnls

        design = np.column_stack([self.basis(n) for n in names])
        # unit u_k: term k at most equal to the curve anywhere
        scale = 1.0 / np.max(design / self.variance[:, None], axis=0)
        scaled = design * scale
        relative = scaled / self.variance[:, None] * self.weight[:, None]
        start, _ = nnls(relative, self.weight)
        start = np.maximum(start, 1e-6)

        def residual(u):
            raw = self.weight * (np.log(np.maximum(scaled @ u, 1e-300)) - self.target)
            return self.whiten(raw)

        def jacobian(u):
            raw = self.weight[:, None] * scaled / np.maximum(scaled @ u, 1e-300)[:, None]
            return self.whiten(raw)

        found = least_squares(
            residual, start, jac=jacobian, bounds=(0.0, np.inf), method="trf", x_scale=1.0
        )
        u = np.where(found.x < 1e-9, 0.0, found.x)
        res = residual(u)
        chi2 = float(res @ res)
        cov = None
        free = np.flatnonzero(u > 0)
        dof = self.tau_h.size - free.size
        if free.size:
            # The sandwich M·Σ·Mᵀ: the fit's own linear map M = (JᵀJ)⁻¹Jᵀ·A (A: weigh and
            # whiten) applied to the log σ̂²'s statistical covariance Σ (χ² scatter, the
            # neighbour correlation) -- the model error steers the fit, it is not scatter.
            jac = jacobian(u)[:, free]
            try:
                inverse = np.linalg.inv(jac.T @ jac)
            except np.linalg.LinAlgError:
                inverse = None
            if inverse is not None:
                mapping = inverse @ jac.T @ self.whiten(np.diag(self.weight))
                spread = mapping @ self.statistical_cov() @ mapping.T
                inflate = max(1.0, chi2 / dof) if dof > 0 else 1.0
                cov = np.zeros((u.size, u.size))
                cov[np.ix_(free, free)] = spread * inflate
                cov = cov * np.outer(scale, scale)
        return Solution(list(names), u * scale, chi2, scaled @ u, cov)
