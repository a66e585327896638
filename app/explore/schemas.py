"""The explorer's query: the station, the schedule and the noise to simulate."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field

from app.explore.scenarios import ExplorerInput


class ExplorerQuery(BaseModel):
    """The explorer's controls, bounded so every request answers in well under a second."""

    method: Literal["two", "four", "both", "seeker"] = "both"
    latitude_deg: float = Field(60.0, ge=-85, le=85)
    preset: Literal["teaching-fog", "tactical-fog", "navigation-fog", "mems"] = "navigation-fog"
    noise: bool = True
    dwell_s: float = Field(30.0, ge=1, le=600)
    runs: int = Field(8, ge=1, le=40)
    drift_deg_h: float = Field(0.0, ge=-5, le=5)
    scale_factor_ppm: float = Field(0.0, ge=-50_000, le=50_000)
    latitude_error_deg: float = Field(0.0, ge=-5, le=5)
    indexing_arcsec: float = Field(0.0, ge=-3600, le=3600)
    indexing_stop: int = Field(2, ge=2, le=4)
    pitch_deg: float = Field(0.0, ge=-30, le=30)
    roll_deg: float = Field(0.0, ge=-30, le=30)
    east_tilt_deg: float = Field(0.0, ge=-10, le=10)
    level_deg: float = Field(0.0, ge=-10, le=10)
    bias_drift_deg_h_per_h: float = Field(1.0, ge=-20, le=20)

    def explorer_input(self) -> ExplorerInput:
        """The heading-error chart's inputs (the drift-order chart has its own)."""
        return ExplorerInput(**self.model_dump(exclude={"bias_drift_deg_h_per_h"}))
