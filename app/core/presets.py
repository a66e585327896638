"""The simulated gyros: each preset's error terms (IEEE Std 952) with their sources.

Every term of :class:`GyroPreset` is one of the measured-rate model's in
:mod:`app.core.simulate`; the values and where they come from are in lab-reference §5.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from app.core.flicker import DEFAULT_BAND_S
from app.core.units import SECONDS_PER_HOUR


@dataclass(frozen=True)
class GyroPreset:
    """One gyro grade and its turntable.  Units in the field names."""

    name: str
    sample_rate_hz: float
    arw_deg_rt_h: float
    bias_instability_deg_h: float  # B: the flicker floor 0.664·B over flicker_band_s
    rrw_deg_h_rt_h: float
    angle_lsb_deg: float
    scale_factor_ppm: float
    constant_bias_deg_h: float
    turn_on_bias_sigma_deg_h: float
    g_sensitivity_deg_h_per_g: float
    misalignment_deg: tuple[float, float]
    indexing_sigma_arcsec: float
    dial_resolution_deg: float
    drift_deg_h_per_h: float = 0.0  # linear bias drift ḃ (warm-up), °/h per hour
    table_tilt_sigma_deg: float = 0.0  # lab turntable: pitch and roll ~ N(0, σ) per session
    misalignment_sigma_deg: float = 0.0  # lab: gyro axis vs dial zero ~ N(0, σ) per session
    warmup_bias_deg_h: float = 0.0  # bias offset at switch-on, decaying as e^(−t/τ_w)
    warmup_time_constant_s: float = 0.0  # τ_w
    warmup_temperature_rise_c: float = 0.0  # case temperature rises by ΔT(1 − e^(−t/τ_w))
    flicker_band_s: tuple[float, float] = DEFAULT_BAND_S  # correlation times of the flicker
    markov_sigma_deg_h: float = 0.0  # a Gauss–Markov bias, where a data sheet gives one
    markov_corr_time_s: float = 0.0
    source: str = ""

    @classmethod
    def noise_only(
        cls,
        rate_hz: float,
        *,
        arw_deg_rt_h: float = 0.0,
        bias_instability_deg_h: float = 0.0,
        rrw_deg_h_rt_h: float = 0.0,
        angle_lsb_deg: float = 0.0,
        flicker_band_s: tuple[float, float] = DEFAULT_BAND_S,
        markov_sigma_deg_h: float = 0.0,
        markov_corr_time_s: float = 0.0,
    ) -> GyroPreset:
        """A gyro with these noise terms and no other error (e.g. a fitted noise model)."""
        return cls(
            name="noise model",
            sample_rate_hz=rate_hz,
            arw_deg_rt_h=arw_deg_rt_h,
            bias_instability_deg_h=bias_instability_deg_h,
            rrw_deg_h_rt_h=rrw_deg_h_rt_h,
            angle_lsb_deg=angle_lsb_deg,
            flicker_band_s=flicker_band_s,
            markov_sigma_deg_h=markov_sigma_deg_h,
            markov_corr_time_s=markov_corr_time_s,
            scale_factor_ppm=0.0,
            constant_bias_deg_h=0.0,
            turn_on_bias_sigma_deg_h=0.0,
            g_sensitivity_deg_h_per_g=0.0,
            misalignment_deg=(0.0, 0.0),
            indexing_sigma_arcsec=0.0,
            dial_resolution_deg=0.0,
        )

    @property
    def dt_s(self) -> float:
        return 1.0 / self.sample_rate_hz

    @property
    def white_sigma_deg_h(self) -> float:
        """Per-sample σ of the angle random walk: 60·N/√Δt (°/h)."""
        return 60.0 * self.arw_deg_rt_h / math.sqrt(self.dt_s)

    def without(self, *errors: str) -> GyroPreset:
        """The same gyro with some error terms switched off (set to zero)."""
        names = {
            "arw": "arw_deg_rt_h",
            "bias_instability": "bias_instability_deg_h",
            "markov": "markov_sigma_deg_h",
            "rrw": "rrw_deg_h_rt_h",
            "quantization": "angle_lsb_deg",
            "scale_factor": "scale_factor_ppm",
            "constant_bias": "constant_bias_deg_h",
            "turn_on_bias": "turn_on_bias_sigma_deg_h",
            "g_sensitivity": "g_sensitivity_deg_h_per_g",
            "indexing": "indexing_sigma_arcsec",
            "dial": "dial_resolution_deg",
            "drift": "drift_deg_h_per_h",
            "warmup": "warmup_bias_deg_h",
        }
        changes: dict = {names[e]: 0.0 for e in errors if e in names}
        if "misalignment" in errors:
            changes["misalignment_deg"] = (0.0, 0.0)
        unknown = set(errors) - set(names) - {"misalignment"}
        if unknown:
            raise ValueError(f"unknown error terms: {sorted(unknown)}")
        return replace(self, **changes)

    def ideal(self) -> GyroPreset:
        return self.without(
            "arw",
            "bias_instability",
            "markov",
            "rrw",
            "quantization",
            "scale_factor",
            "constant_bias",
            "turn_on_bias",
            "g_sensitivity",
            "misalignment",
            "indexing",
            "dial",
            "drift",
            "warmup",
        )


PRESETS: dict[str, GyroPreset] = {
    "teaching-fog": GyroPreset(
        name="teaching-fog",
        sample_rate_hz=0.1,  # one reading every 10 s, each the output averaged over 10 s
        arw_deg_rt_h=0.005,
        bias_instability_deg_h=0.03,
        rrw_deg_h_rt_h=0.0,
        angle_lsb_deg=1.0 / SECONDS_PER_HOUR,  # 1″ pulses: 0.1 °/h steps over 10 s
        scale_factor_ppm=500.0,
        constant_bias_deg_h=0.0,
        turn_on_bias_sigma_deg_h=1.0,
        g_sensitivity_deg_h_per_g=0.1,
        misalignment_deg=(0.0, 0.0),
        indexing_sigma_arcsec=60.0,
        table_tilt_sigma_deg=0.1,
        misalignment_sigma_deg=0.5,
        dial_resolution_deg=0.1,
        warmup_bias_deg_h=1.0,
        warmup_time_constant_s=300.0,
        warmup_temperature_rise_c=8.0,
        flicker_band_s=(10.0, 1.0e5),  # from the reading interval to a day
        source="The handout's own data (lab-reference §2, §5). Reading interval: one reading "
        "every 10 s, each the FOG's output averaged over those 10 s (the '10 s smoothing' of "
        "FOG data sheets). Per-reading scatter: 60·N/√10 = 0.095 °/h from ARW plus 0.04 °/h "
        "from the 1″ angle pulses, which make the 0.09–0.11 °/h steps: ≈ 0.1 °/h as in the "
        "handout. B 0.03 °/h as flicker noise (a flat Allan floor of 0.02 °/h from the reading "
        "interval to a day), no rate random walk resolved in the handout's data, scale factor "
        "500 ppm, turn-on bias 1 °/h: a mid-grade "
        "(tactical-class) FOG, never better than the navigation preset. Table: indexing 60″, "
        "dial 0.1°, level σ 0.1°, axis-to-dial misalignment σ 0.5° (the handout's latitude "
        "error of 1–2 %). Warm-up: bias 1 °/h decaying with τ = 5 min while the case warms "
        "by 8 °C.",
    ),
    "tactical-fog": GyroPreset(
        name="tactical-fog",
        sample_rate_hz=10.0,
        arw_deg_rt_h=0.012,
        bias_instability_deg_h=0.05,
        rrw_deg_h_rt_h=0.0,
        angle_lsb_deg=1e-6,
        scale_factor_ppm=100.0,
        constant_bias_deg_h=0.0,
        turn_on_bias_sigma_deg_h=0.5,
        g_sensitivity_deg_h_per_g=0.05,
        misalignment_deg=(0.0, 0.0),
        indexing_sigma_arcsec=30.0,
        table_tilt_sigma_deg=0.05,
        misalignment_sigma_deg=0.05,
        dial_resolution_deg=0.01,
        warmup_bias_deg_h=0.2,
        warmup_time_constant_s=180.0,
        warmup_temperature_rise_c=5.0,
        flicker_band_s=(0.1, 1.0e5),  # from the sample period to a day
        source="KVH DSP-1750 data sheet (lab-reference §5): ARW ≤ 0.012 °/√h, bias "
        "instability ≤ 0.05 °/h (flicker: a flat Allan floor from 0.1 s to a day), no rate random "
        "walk or correlation time given; scale factor ~100 ppm; warm-up 0.2 °/h with τ = 3 min.",
    ),
    "navigation-fog": GyroPreset(
        name="navigation-fog",
        sample_rate_hz=10.0,
        arw_deg_rt_h=0.002,
        bias_instability_deg_h=0.008,
        rrw_deg_h_rt_h=0.0,
        angle_lsb_deg=1e-7,
        scale_factor_ppm=10.0,
        constant_bias_deg_h=0.0,
        turn_on_bias_sigma_deg_h=0.01,
        g_sensitivity_deg_h_per_g=0.0,
        misalignment_deg=(0.0, 0.0),
        indexing_sigma_arcsec=10.0,
        table_tilt_sigma_deg=0.01,
        misalignment_sigma_deg=0.01,
        dial_resolution_deg=0.001,
        warmup_bias_deg_h=0.01,
        warmup_time_constant_s=600.0,
        warmup_temperature_rise_c=3.0,
        flicker_band_s=(0.1, 1.0e5),  # from the sample period to a day
        source="Navigation-grade FOG (lab-reference §5): ARW ≈ 0.002 °/√h, B < 0.01 °/h "
        "(0.008, flicker); "
        "warm-up 0.01 °/h with τ = 10 min.",
    ),
    "mems": GyroPreset(
        name="mems",
        sample_rate_hz=10.0,
        arw_deg_rt_h=0.5,
        bias_instability_deg_h=10.0,
        rrw_deg_h_rt_h=5.0,
        angle_lsb_deg=250.0 / 2**15 * 0.1,  # 16 bits over ±250 °/s, at 10 Hz
        scale_factor_ppm=3000.0,
        constant_bias_deg_h=0.0,
        turn_on_bias_sigma_deg_h=360.0,
        g_sensitivity_deg_h_per_g=36.0,
        misalignment_deg=(0.0, 0.0),
        indexing_sigma_arcsec=60.0,
        table_tilt_sigma_deg=0.2,
        misalignment_sigma_deg=1.0,
        dial_resolution_deg=0.1,
        warmup_bias_deg_h=20.0,
        warmup_time_constant_s=60.0,
        warmup_temperature_rise_c=10.0,
        flicker_band_s=(0.1, 1.0e5),  # from the sample period to a day
        source="Consumer MEMS (lab-reference §5): B ≈ 10 °/h (flicker), N ≈ 0.3–1 °/√h, "
        "K 5 °/h/√h; turn-on bias "
        "0.1 °/s; g-sensitivity 0.01 °/s/g; 16-bit output over ±250 °/s; warm-up 20 °/h "
        "with τ = 1 min.",
    ),
}


def get_preset(name: str) -> GyroPreset:
    """The preset called ``name``.

    Parameters
    ----------
    name : str
        One of :data:`PRESETS`' keys.

    Returns
    -------
    GyroPreset
        The preset.

    Raises
    ------
    ValueError
        For an unknown name (the message lists the known ones).
    """
    try:
        return PRESETS[name]
    except KeyError:
        raise ValueError(f"unknown preset {name!r}; choose from {', '.join(PRESETS)}") from None
