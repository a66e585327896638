"""The lab's request and response models (pydantic): the REST API's sessions, uploads and
results, and the session page's own request bodies."""

from __future__ import annotations

from datetime import datetime
from typing import Annotated, Literal

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, StrictFloat, StrictInt

from app.core.units import ALIASES
from app.lab.store import MAX_SAMPLES_PER_POSITION, POSITIONS
from app.web.deps import MAX_ID


def _unit_by_its_canonical_name(value: object) -> object:
    """The aliases "°/h", "dph", "dps", "deg/hr", "rad/sec" as their unit's canonical name,
    as the query's ``?unit=`` and the pages take them; anything else is left to be refused."""
    return ALIASES.get(value.strip(), value.strip()) if isinstance(value, str) else value


# the canonical names are the schema's choices; their aliases are taken as they
RateUnit = Annotated[
    Literal["deg/h", "deg/s", "rad/s"], BeforeValidator(_unit_by_its_canonical_name)
]


class Station(BaseModel):
    model_config = ConfigDict(strict=True, allow_inf_nan=False, extra="forbid")
    latitude_deg: float = Field(ge=-90, le=90)
    earth_rate_deg_h: float = Field(gt=0, lt=1000, default=15.041)


class HeadingSettings(BaseModel):
    model_config = ConfigDict(strict=True, allow_inf_nan=False, extra="forbid")
    rotation: Literal["ccw", "cw"] = "ccw"
    start_angle_deg: float = 0.0


class LatitudeSettings(BaseModel):
    model_config = ConfigDict(strict=True, allow_inf_nan=False, extra="forbid")
    start_angle_deg: float = 0.0
    step_deg: float = 90.0


class SessionCreate(BaseModel):
    model_config = ConfigDict(
        strict=True,
        allow_inf_nan=False,
        extra="forbid",  # a misspelt field ("units", "start_angle") is said, not dropped
        json_schema_extra={
            "examples": [
                {
                    "title": "Bench 3, Tuesday",
                    "station": {"latitude_deg": 39.93, "earth_rate_deg_h": 15.04},
                    "heading": {"rotation": "ccw", "start_angle_deg": 0.0},
                    "latitude": {"start_angle_deg": 0.0, "step_deg": 90.0},
                }
            ]
        },
    )
    title: str = Field(default="", max_length=200)
    assignment_id: int | None = Field(default=None, ge=1, le=MAX_ID)
    station: Station | None = None
    heading: HeadingSettings = HeadingSettings()
    latitude: LatitudeSettings = LatitudeSettings()
    simulator_preset: str = Field(default="teaching-fog", max_length=32)
    symmetric_order: bool = Field(
        default=False,
        description="Record 1-2-3-4-4-3-2-1: positions 5–8 revisit 4–1, so a linear drift "
        "cancels (and, with times, is fitted).",
    )


class PositionSummary(BaseModel):
    part: str
    position: int
    angle_deg: float
    n_samples: int
    source: str
    recorded_at: datetime


class SessionOut(BaseModel):
    id: int
    title: str
    assignment_id: int | None
    status: str
    station: Station
    heading: HeadingSettings
    latitude: LatitudeSettings
    min_readings: int
    symmetric_order: bool
    positions: list[PositionSummary]
    created_at: datetime
    updated_at: datetime


class PositionUpload(BaseModel):
    model_config = ConfigDict(
        strict=True,
        allow_inf_nan=False,
        extra="forbid",  # a misspelt field ("units", "start_angle") is said, not dropped
        json_schema_extra={
            "examples": [
                {
                    "samples": [
                        10.74,
                        10.65,
                        10.84,
                        10.46,
                        10.65,
                        10.65,
                        10.74,
                        10.65,
                        10.84,
                        10.84,
                    ],
                    "unit": "deg/h",
                }
            ]
        },
    )
    samples: list[StrictFloat | StrictInt] = Field(
        min_length=1, max_length=MAX_SAMPLES_PER_POSITION
    )
    unit: RateUnit = "deg/h"
    angle_deg: StrictFloat | StrictInt | None = Field(
        default=None, description="the dial angle; default: from the session's settings"
    )
    times_s: list[StrictFloat | StrictInt] | None = Field(
        default=None,
        max_length=MAX_SAMPLES_PER_POSITION,
        description="each sample's time in seconds, on one clock for the whole session "
        "(e.g. since switch-on): with the symmetric order the fit then estimates a linear "
        "bias drift",
    )
    temperatures_c: list[StrictFloat | StrictInt] | None = Field(
        default=None,
        max_length=MAX_SAMPLES_PER_POSITION,
        description="each sample's gyro case temperature in °C, when the instrument "
        "reports it (a change over 1 °C while recording is flagged: warm-up)",
    )
    offset: StrictInt | None = Field(
        default=None,
        ge=0,
        description="append only: index of the first sample, so a "
        "retried batch is not stored twice",
    )


class UploadOut(BaseModel):
    session_id: int
    part: str
    position: int
    n_samples: int = Field(description="samples now stored for this position")
    added: int


class WarmUpOut(BaseModel):
    """Whether the bias drifted through the run (a gyro still warming up)."""

    flagged: bool = Field(
        description="the drift is significant (|z| ≥ 3) or the case "
        "temperature changed by more than 1 °C"
    )
    drift_rate: float | None = Field(description="the linear bias drift ḃ seen")
    drift_sigma: float | None
    drift_unit: Literal["deg/h per h", "deg/h per reading"]
    z: float | None
    witnesses: list[str] = Field(description="closure, trend, temperature or combined")
    temperature_change_c: float | None
    shift: dict[str, float] | None = Field(
        description="how far the drift moved the result (added in quadrature to its 1σ)"
    )
    wait_minutes: int


class HeadingOut(BaseModel):
    part: Literal["heading"]
    n_positions: int
    samples_per_position: list[int]
    position_means_deg_h: list[float]
    position_sems_deg_h: list[float | None]
    position_sigmas_deg_h: list[float] | None = Field(
        description="the 1σ(-equivalent) of each position mean that the result propagates"
    )
    azimuth_deg: float
    azimuth_sigma_deg: float | None
    theta_deg: float
    rotate_direction: Literal["clockwise", "counterclockwise"]
    rotate_deg: float
    then_axis_points: Literal["north", "south"]
    bias_deg_h: float
    bias_sigma_deg_h: float | None = Field(None, description="1σ of the bias b (°/h)")
    amplitude_deg_h: float
    amplitude_sigma_deg_h: float | None
    closure_residual_deg_h: float | None
    closure_sigma_deg_h: float | None
    uncertainty_model: Literal["white", "closure", "allan"] | None = Field(
        description="what the 1σ assumes: white noise (Student-t), the closure residual "
        "(one degree of freedom), or the gyro's noise model"
    )
    drift_deg_h_per_h: float | None = Field(
        description="linear bias drift, fitted when 5+ positions have times on one clock"
    )
    drift_sigma_deg_h_per_h: float | None
    azimuth_error_deg: float | None
    azimuth_noise_sigma_deg: float | None = Field(
        description="the 1σ from the noise alone, before a flagged drift widened it"
    )
    warm_up: WarmUpOut | None


class LatitudeOut(BaseModel):
    part: Literal["latitude"]
    n_positions: int
    samples_per_position: list[int]
    position_means_deg_h: list[float]
    position_sems_deg_h: list[float | None]
    position_sigmas_deg_h: list[float] | None
    latitude_deg: float
    latitude_sigma_deg: float | None
    earth_rate_deg_h: float
    earth_rate_sigma_deg_h: float | None
    bias_deg_h: float
    bias_sigma_deg_h: float | None = Field(None, description="1σ of the bias b (°/h)")
    latitude_error_percent: float | None
    latitude_error_deg: float | None = Field(description="φ − φ0 (°)")
    earth_rate_error_percent: float
    closure_residual_deg_h: float | None
    closure_sigma_deg_h: float | None
    uncertainty_model: Literal["white", "closure", "allan"] | None
    drift_deg_h_per_h: float | None
    drift_sigma_deg_h_per_h: float | None
    latitude_noise_sigma_deg: float | None
    earth_rate_noise_sigma_deg_h: float | None
    warm_up: WarmUpOut | None


class FlagOut(BaseModel):
    key: str = Field(description="the flag's message key, e.g. flag.unit_slip")
    params: dict[str, str | int | float | None] = Field(description="the message's values")
    message: str = Field(description="the message, in English")


class ResultsOut(BaseModel):
    heading: HeadingOut | None
    latitude: LatitudeOut | None
    problems: dict[str, str] = Field(default_factory=dict, description="why a part has no result")
    flags: dict[str, list[FlagOut]] = Field(
        default_factory=dict,
        description="each part's data-quality flags, as the lab page shows them: too few "
        "readings, spikes, gaps, a noisy position, a drifting bias (warm-up), a closure "
        "residual beyond 3σ, readings saved in another unit than recorded",
    )


class AttemptOut(BaseModel):
    session_id: int
    attempt: int
    submitted_at: datetime
    late: bool
    status: str


class TrimIn(BaseModel):
    model_config = ConfigDict(extra="forbid")
    trim: int = Field(
        ge=0, le=10_000_000, strict=True, description="readings to leave out at the start"
    )


class TrimOut(BaseModel):
    part: str
    position: int
    n_samples: int
    trim_start: int
    n_used: int


# The session page's request bodies (its fetch() calls to /lab/sessions/{id}/...)

Part = Literal["heading", "latitude"]


class ManualReadings(BaseModel):
    """Readings typed into the grid: one list per position (positions left empty are kept)."""

    part: Part
    unit: str = "deg/h"
    columns: dict[int, Annotated[list[StrictFloat | StrictInt], Field(max_length=100_000)]] = Field(
        max_length=POSITIONS
    )


class CsvUpload(BaseModel):
    part: Part
    unit: str = "deg/h"
    text: str
    # a file of one position's record (a gyro logger's): the position it was recorded at
    position: int | None = Field(default=None, ge=1, le=POSITIONS, strict=True)
    # an IMU's record of several axes: the column of the gyro's axis (a header cell, or a
    # number from 1)
    column: str | None = Field(default=None, min_length=1, max_length=200)


class Turn(BaseModel):
    part: Part
    position: int = Field(ge=1, le=POSITIONS, strict=True)


class Trim(BaseModel):
    part: Part
    position: int = Field(ge=1, le=POSITIONS, strict=True)
    trim: int = Field(ge=0, le=10_000_000, strict=True)


class Plane(BaseModel):
    dial_deg: float = Field(ge=-360, le=360, allow_inf_nan=False, strict=True)


class PlanPointOut(BaseModel):
    order: Literal["1234", "12344321"] = Field(
        description="four positions, or the symmetric eight (1-2-3-4-4-3-2-1)"
    )
    dwell_s: float = Field(description="recording time per position (s)")
    total_s: float = Field(description="recording time of the whole part, turns not counted")
    heading_sigma_deg: float = Field(description="expected 1σ of the heading, over azimuths")
    latitude_sigma_deg: float
    earth_rate_sigma_deg_h: float


class PlanOut(BaseModel):
    """The accuracy planner: the gyro's noise alone (not indexing or reading errors)."""

    points: list[PlanPointOut]
    best: dict[str, PlanPointOut] = Field(description="per order, the smallest heading σ")
    near_best: dict[str, PlanPointOut] = Field(
        description="per order, the shortest dwell within 10 % of the best heading σ"
    )
    source: Literal["station", "preset"] = Field(
        description="the Allan characterisation uploaded for the station, or the preset's model"
    )
    preset: str | None
    quoted_dwell_s: float
