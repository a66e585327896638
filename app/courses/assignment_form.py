"""The assignment form (create and settings): one pydantic model holds every field's
default, type and range; every wrong field is refused at once (:class:`FieldProblems`,
each message shown beside its field)."""

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
    ValidationInfo,
    field_validator,
)

from app.core.exceptions import FieldProblems, UserError
from app.core.presets import PRESETS
from app.core.text_files import shown_name
from app.core.typed_numbers import parse_typed_number
from app.models import Assignment, InputMethod, LatePolicy, RevealTruth
from app.web.local_time import local_input_to_utc, utc_to_local_input

RECORDING_METHODS = (InputMethod.manual, InputMethod.csv, InputMethod.simulator)
HANDOUT_LATITUDE_DEG = 39.93


def _blank_is_none(value: Any) -> Any:
    return None if isinstance(value, str) and not value.strip() else value


def _typed_number(value: Any) -> Any:
    """A number as typed ("12,5", "−3"): as a float; anything else as it is (refused by
    the field's type)."""
    if isinstance(value, str) and value.strip():
        try:
            return parse_typed_number(value)
        except ValueError:
            return value
    return value


Optional = Annotated[Any, BeforeValidator(_blank_is_none)]
NUMBER_TYPES = (float, float | None)


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

    @field_validator("*", mode="before")
    @classmethod
    def _as_typed(cls, value: Any, info: ValidationInfo) -> Any:
        """Every number field takes a number as people type it ("12,5", "−3")."""
        if cls.model_fields[info.field_name].annotation in NUMBER_TYPES:
            return _typed_number(value)
        return value

    @field_validator("title")
    @classmethod
    def _shown_title(cls, value: str) -> str:
        """A title as pages show it: no bidirectional controls, which would reorder the
        text beside it on every page and export that shows it."""
        return shown_name(value)

    def assignment(self, course_id: int = 0, zone_name: str | None = None) -> Assignment:
        """The unsaved assignment (the form's rules are checked by ``rule_problems``)."""
        methods = [m for m in self.methods if m in RECORDING_METHODS]
        criteria = parse_rubric(self.rubric)
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
                points = parse_typed_number(match["points"])
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


FIELD_LABELS = {  # the form's fields in page order, with their labels' keys
    "title": "assignment.title",
    "instructions": "assignment.instructions",
    "latitude_deg": "assignment.latitude",
    "earth_rate_deg_h": "assignment.earth_rate",
    "methods": "assignment.methods",
    "simulator_preset": "assignment.preset",
    "min_readings": "assignment.min_readings",
    "due_at": "assignment.due",
    "late_policy": "assignment.late_policy",
    "group_size": "assignment.group_size",
    "max_points": "assignment.max_points",
    "rubric": "assignment.rubric",
    "azimuth_min_deg": "assignment.azimuth_min",
    "azimuth_max_deg": "assignment.azimuth_max",
    "turn_on_bias_max_deg_h": "assignment.turn_on_bias_max",
    "indexing_sigma_arcsec": "assignment.indexing_sigma",
    "table_tilt_max_deg": "assignment.table_tilt_max",
    "misalignment_max_deg": "assignment.misalignment_max",
    "true_heading_deg": "assignment.true_heading",
    "tolerance_heading_deg": "assignment.tol_heading",
    "tolerance_latitude_pct": "assignment.tol_latitude",
    "tolerance_earth_rate_pct": "assignment.tol_earth_rate",
    "max_attempts": "assignment.max_attempts",
    "reveal_truth": "assignment.reveal",
}
ADVANCED_FIELDS = (  # inside the form's "advanced" section (opened when one is refused)
    "azimuth_min_deg",
    "azimuth_max_deg",
    "turn_on_bias_max_deg_h",
    "indexing_sigma_arcsec",
    "table_tilt_max_deg",
    "misalignment_max_deg",
    "true_heading_deg",
    "tolerance_heading_deg",
    "tolerance_latitude_pct",
    "tolerance_earth_rate_pct",
    "max_attempts",
    "reveal_truth",
)
GRADING_FIELDS = ("group_size", "max_points", "rubric")


def form_context(problems: dict[str, UserError] | None = None) -> dict[str, Any]:
    """What the form's template needs beside its values: the refused fields and their
    labels, and which fields sit in its folded sections."""
    return {
        "problems": problems or {},
        "field_labels": FIELD_LABELS,
        "grading_fields": GRADING_FIELDS,
        "advanced_fields": ADVANCED_FIELDS,
    }


def parse_assignment_form(values: dict[str, Any], zone_name: str | None = None) -> Assignment:
    """The form's values (strings; ``methods`` a list) as an unsaved Assignment, or
    :class:`FieldProblems` with every wrong field.  The due date is typed in ``zone_name``
    (the course's time zone) and stored in UTC."""
    problems: dict[str, UserError] = {}
    form = None
    try:
        form = AssignmentForm.model_validate(values)
    except ValidationError as error:
        for item in error.errors():
            field = str(item["loc"][0]) if item["loc"] else ""
            typed = values.get(field)
            blank = isinstance(typed, str) and not typed.strip()
            problems.setdefault(field, _field_problem(field, "missing" if blank else item["type"]))
    for field, problem in rule_problems(values, form).items():
        problems.setdefault(field, problem)
    if problems:
        order = list(FIELD_LABELS)
        ranked = sorted(problems, key=lambda f: order.index(f) if f in order else len(order))
        raise FieldProblems({field: problems[field] for field in ranked})
    return form.assignment(zone_name=zone_name)


def rule_problems(values: dict[str, Any], form: AssignmentForm | None) -> dict[str, UserError]:
    """What the fields' types do not say: a title, a way of recording, a known gyro, a
    rubric whose lines parse and add up to the maximum points."""
    problems: dict[str, UserError] = {}
    if not str(values.get("title", "")).strip():
        problems["title"] = UserError("assignment.title_required")
    methods = values.get("methods", list(RECORDING_METHODS))
    if not [m for m in methods if m in RECORDING_METHODS]:
        problems["methods"] = UserError("assignment.methods_required")
    if values.get("simulator_preset", "teaching-fog") not in PRESETS:
        problems["simulator_preset"] = UserError("assignment.bad_preset")
    try:
        criteria = parse_rubric(str(values.get("rubric", "")))
    except UserError as problem:
        problems["rubric"] = problem
        return problems
    total = sum(c["points"] for c in criteria)
    if form is not None and criteria and abs(total - form.max_points) > 1e-9:
        problems["rubric"] = UserError(
            "assignment.rubric_total", total=f"{total:g}", max=f"{form.max_points:g}"
        )
    return problems


def _field_problem(field: str, kind: str) -> UserError:
    """A type or range refusal in the user's words (shown beside the field)."""
    if field == "due_at":
        return UserError("assignment.bad_due")
    if field in ("late_policy", "reveal_truth", "group_size") and kind != "missing":
        return UserError("form.bad_choice")
    if kind == "missing":
        return UserError("form.required")
    info = AssignmentForm.model_fields.get(field)
    metadata = info.metadata if info is not None else []
    low = next((m.ge for m in metadata if hasattr(m, "ge")), None)
    low = low if low is not None else next((m.gt for m in metadata if hasattr(m, "gt")), None)
    high = next((m.le for m in metadata if hasattr(m, "le")), None)
    whole = info is not None and info.annotation is int
    if kind.startswith("string_too_long"):
        limit = next((m.max_length for m in metadata if hasattr(m, "max_length")), None)
        return UserError("form.too_long", limit=limit)
    if low is not None and high is not None:
        key = "form.whole_between" if whole else "form.between"
        return UserError(key, low=f"{low:g}", high=f"{high:g}")
    return UserError("form.not_a_number")


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
