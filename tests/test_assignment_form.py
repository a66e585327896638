"""The assignment form's one model: defaults, ranges, and the field each problem names."""

from __future__ import annotations

from datetime import UTC

import pytest

from app.core.exceptions import UserError
from app.courses.assignment_form import form_values, parse_assignment_form

GOOD = {"title": "Find north", "latitude_deg": "39.93", "methods": ["manual", "simulator"]}


def test_defaults_come_from_the_model_and_blank_optionals_are_none():
    assignment = parse_assignment_form({**GOOD, "turn_on_bias_max_deg_h": "  "})
    assert assignment.allowed_methods == "manual,simulator"
    assert assignment.earth_rate_deg_h == 15.041 and assignment.min_readings == 10
    assert assignment.late_policy == "accept" and assignment.reveal_truth == "after_grading"
    assert assignment.turn_on_bias_max_deg_h is None and assignment.due_at is None
    shown = form_values()
    assert shown["earth_rate_deg_h"] == "15.041" and shown["azimuth_max_deg"] == "360"
    assert shown["methods"] == ["manual", "csv", "simulator"] and shown["latitude_deg"] == "39.93"


def test_values_round_trip_through_the_settings_form():
    assignment = parse_assignment_form(
        {**GOOD, "min_readings": "12.0", "due_at": "2030-05-01T09:30", "table_tilt_max_deg": "2"}
    )
    assert assignment.min_readings == 12 and assignment.table_tilt_max_deg == 2.0
    # typed in the server's default zone, Asia/Shanghai (UTC+8), stored in UTC
    assert assignment.due_at.tzinfo == UTC and assignment.due_at.hour == 1
    again = parse_assignment_form(form_values(assignment))
    assert again.model_dump(exclude={"id", "created_at"}) == assignment.model_dump(
        exclude={"id", "created_at"}
    )


@pytest.mark.parametrize(
    ("change", "key", "params"),
    [
        ({"title": " "}, "assignment.title_required", {}),
        ({"methods": ["telepathy"]}, "assignment.methods_required", {}),
        ({"simulator_preset": "ring-laser"}, "assignment.bad_preset", {}),
        ({"late_policy": "maybe"}, "assignment.bad_choice", {"field": "late_policy"}),
        ({"reveal_truth": "always"}, "assignment.bad_choice", {"field": "reveal_truth"}),
        ({"due_at": "tomorrow"}, "assignment.bad_due", {}),
        ({"latitude_deg": "north"}, "assignment.not_a_number", {"field": "latitude_deg"}),
        ({"latitude_deg": ""}, "assignment.not_a_number", {"field": "latitude_deg"}),
        (
            {"latitude_deg": "91"},
            "assignment.out_of_range",
            {"field": "latitude_deg", "low": -90, "high": 90},
        ),
        (
            {"earth_rate_deg_h": "inf"},
            "assignment.out_of_range",
            {"field": "earth_rate_deg_h", "low": 1, "high": 100},
        ),
        (
            {"max_attempts": "101"},
            "assignment.out_of_range",
            {"field": "max_attempts", "low": 0, "high": 100},
        ),
        (
            {"misalignment_max_deg": "-1"},
            "assignment.out_of_range",
            {"field": "misalignment_max_deg", "low": 0, "high": 10},
        ),
        ({"min_readings": "ten"}, "assignment.not_a_number", {"field": "min_readings"}),
    ],
)
def test_each_problem_names_its_field(change, key, params):
    with pytest.raises(UserError) as caught:
        parse_assignment_form({**GOOD, **change})
    assert (caught.value.key, caught.value.params) == (key, params)
