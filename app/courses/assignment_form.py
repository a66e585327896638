"""The assignment form (create and settings): one pydantic model holds every field's
default, type and range; a wrong field becomes one :class:`UserError` naming it."""

from __future__ import annotations

import json
import math
import re
from datetime import datetime
from typing import Annotated, Any

from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    ValidationError,
    field_validator,
)

from app.core.exceptions import UserError
from app.core.presets import PRESETS
from app.core.readings import parse_decimal
from app.models import Assignment, InputMethod, LatePolicy, RevealTruth
from app.web.local_time import local_input_to_utc, utc_to_local_input

RECORDING_METHODS = (InputMethod.manual, InputMethod.csv, InputMethod.simulator)
HANDOUT_LATITUDE_DEG = 39.93


def _blank_is_none(value: Any) -> Any:
    return None if isinstance(value, str) and not value.strip() else value


Optional = Annotated[Any, BeforeValidator(_blank_is_none)]


class AssignmentForm(BaseModel):
    """What a teacher sets: station, ways of recording, gyro, truth ranges, rules."""

    model_config = ConfigDict(str_strip_whitespace=True, allow_inf_nan=False)

    title: str = Field(default="", max_length=200)
    instructions: str = Field(default="", max_length=20_000)
    latitude_deg: float = Field(ge=-90, le=90)
    earth_rate_deg_h: float = Field(default=15.041, ge=1, le=100)
    methods: list[str] = Field(default_factory=lambda: list(RECORDING_METHODS))
    simulator_preset: str = "teaching-fog"
    min_readings: int = Field(default=10, ge=2, le=100_000)
    due_at: Annotated[datetime | None, BeforeValidator(_blank_is_none)] = None
    azimuth_min_deg: float = Field(default=0.0, ge=0, le=360)
    azimuth_max_deg: float = Field(default=360.0, ge=0, le=360)
    turn_on_bias_max_deg_h: Annotated[float | None, BeforeValidator(_blank_is_none)] = Field(
        default=None, ge=0, le=10_000
    )
    indexing_sigma_arcsec: Annotated[float | None, BeforeValidator(_blank_is_none)] = Field(
        default=None, ge=0, le=36_000
    )
    table_tilt_max_deg: Annotated[float | None, BeforeValidator(_blank_is_none)] = Field(
        default=None, ge=0, le=30
    )
    misalignment_max_deg: Annotated[float | None, BeforeValidator(_blank_is_none)] = Field(
        default=None, ge=0, le=10
    )
    true_heading_deg: Annotated[float | None, BeforeValidator(_blank_is_none)] = Field(
        default=None, ge=0, le=360
    )
    tolerance_heading_deg: float = Field(default=2.0, ge=0, le=180)
    tolerance_latitude_pct: float = Field(default=5.0, ge=0, le=1000)
    tolerance_earth_rate_pct: float = Field(default=5.0, ge=0, le=1000)
    max_attempts: int = Field(default=3, ge=0, le=100)
    late_policy: LatePolicy = LatePolicy.accept
    reveal_truth: RevealTruth = RevealTruth.after_grading
    max_points: float = Field(default=100.0, gt=0, le=100_000)
    group_size: int = Field(default=1, ge=1, le=3)  # lab partners per session
    # one criterion per line, "name | points" (a rubric is optional)
    rubric: str = Field(default="", max_length=20_000)

    @field_validator("min_readings", "max_attempts", "group_size", mode="before")
    @classmethod
    def _whole_number(cls, value: Any) -> Any:
        """A count typed as "10.0" is 10 (the part after the point is dropped)."""
        try:
            number = float(str(value).strip())
        except ValueError:
            return value
        return int(number) if math.isfinite(number) else value

    def assignment(self, course_id: int = 0, zone_name: str | None = None) -> Assignment:
        if not self.title:
            raise UserError("assignment.title_required")
        methods = [m for m in self.methods if m in RECORDING_METHODS]
        if not methods:
            raise UserError("assignment.methods_required")
        if self.simulator_preset not in PRESETS:
            raise UserError("assignment.bad_preset")
        criteria = parse_rubric(self.rubric)
        total = sum(c["points"] for c in criteria)
        if criteria and abs(total - self.max_points) > 1e-9:
            raise UserError(
                "assignment.rubric_total", total=f"{total:g}", max=f"{self.max_points:g}"
            )
        fields = self.model_dump(exclude={"methods", "rubric", "due_at"})
        due = local_input_to_utc(self.due_at, zone_name) if self.due_at else None
        return Assignment(
            course_id=course_id,
            allowed_methods=",".join(methods),
            rubric=json.dumps(criteria, ensure_ascii=False),
            due_at=due,
            **fields,
        )


RUBRIC_LINE = re.compile(r"^(?P<name>.+?)\s*[|｜]\s*(?P<points>[^|｜]+)$")


def parse_rubric(text: str) -> list[dict]:
    """Rubric lines ``name | points`` → ``[{"name", "points"}]``; a wrong line raises a
    UserError naming it."""
    criteria = []
    for number, line in enumerate(text.splitlines(), start=1):
        line = line.strip()
        if not line:
            continue
        match = RUBRIC_LINE.match(line)
        points = math.nan
        if match:
            try:
                points = parse_decimal(match["points"].strip())
            except ValueError:
                points = math.nan
        if not match or not math.isfinite(points) or not 0 < points <= 100_000:
            raise UserError("assignment.bad_rubric", line=number)
        criteria.append({"name": match["name"].strip()[:200], "points": points})
    if len(criteria) > 50:
        raise UserError("assignment.rubric_too_long", limit=50)
    return criteria


def rubric_text(rubric_json: str) -> str:
    """A stored rubric as the form's lines."""
    try:
        criteria = json.loads(rubric_json or "[]")
    except ValueError:
        return ""
    return "\n".join(f"{c['name']} | {c['points']:g}" for c in criteria if isinstance(c, dict))


def parse_assignment_form(values: dict[str, Any], zone_name: str | None = None) -> Assignment:
    """The form's values (strings; ``methods`` a list) as an unsaved Assignment, or a
    UserError naming the first wrong field.  The due date is typed in ``zone_name`` (the
    course's time zone) and stored in UTC."""
    try:
        form = AssignmentForm.model_validate(values)
    except ValidationError as error:
        raise _problem(error) from None
    return form.assignment(zone_name=zone_name)


def _problem(error: ValidationError) -> UserError:
    first = error.errors()[0]
    field = str(first["loc"][0]) if first["loc"] else ""
    kind = first["type"]
    if field == "due_at":
        return UserError("assignment.bad_due")
    if field in ("late_policy", "reveal_truth"):
        return UserError("assignment.bad_choice", field=field)
    if field == "latitude_deg" and kind == "missing":
        return UserError("assignment.not_a_number", field=field)
    metadata = AssignmentForm.model_fields[field].metadata if field else []
    low = next((m.ge for m in metadata if hasattr(m, "ge")), None)
    high = next((m.le for m in metadata if hasattr(m, "le")), None)
    if kind in ("greater_than_equal", "less_than_equal", "finite_number") and low is not None:
        return UserError("assignment.out_of_range", field=field, low=low, high=high)
    return UserError("assignment.not_a_number", field=field)


def form_values(
    assignment: Assignment | None = None, zone_name: str | None = None
) -> dict[str, Any]:
    """The form's fields as the page shows them: an assignment's, or the defaults."""

    def text(value) -> str:
        if value is None:
            return ""
        return f"{value:g}" if isinstance(value, float) else str(value)

    if assignment is None:
        defaults = {
            name: field.get_default(call_default_factory=True)
            for name, field in AssignmentForm.model_fields.items()
            if name != "latitude_deg"
        }
        values = {name: text(value) for name, value in defaults.items() if name != "methods"}
        values["latitude_deg"] = f"{HANDOUT_LATITUDE_DEG:g}"  # a suggestion: the handout's
        values["methods"] = list(RECORDING_METHODS)
        return values
    values = {
        name: text(getattr(assignment, name))
        for name in AssignmentForm.model_fields
        if name not in ("methods", "due_at", "rubric")
    }
    values["methods"] = assignment.methods
    values["due_at"] = utc_to_local_input(assignment.due_at, zone_name)
    values["rubric"] = rubric_text(assignment.rubric)
    return values
