"""The assignment form's one model: defaults, ranges, and the field each problem names."""

from __future__ import annotations

from datetime import UTC

import pytest

from app.core.exceptions import FieldProblems
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
    ("change", "field", "key", "params"),
    [
        ({"title": " "}, "title", "assignment.title_required", {}),
        ({"methods": ["telepathy"]}, "methods", "assignment.methods_required", {}),
        ({"simulator_preset": "ring-laser"}, "simulator_preset", "assignment.bad_preset", {}),
        ({"late_policy": "maybe"}, "late_policy", "form.bad_choice", {}),
        ({"reveal_truth": "always"}, "reveal_truth", "form.bad_choice", {}),
        ({"due_at": "tomorrow"}, "due_at", "assignment.bad_due", {}),
        ({"latitude_deg": "north"}, "latitude_deg", "form.between", {"low": "-90", "high": "90"}),
        ({"latitude_deg": ""}, "latitude_deg", "form.required", {}),
        ({"latitude_deg": "91"}, "latitude_deg", "form.between", {"low": "-90", "high": "90"}),
        (
            {"earth_rate_deg_h": "inf"},
            "earth_rate_deg_h",
            "form.between",
            {"low": "1", "high": "100"},
        ),
        (
            {"max_attempts": "101"},
            "max_attempts",
            "form.whole_between",
            {"low": "0", "high": "100"},
        ),
        (
            {"misalignment_max_deg": "-1"},
            "misalignment_max_deg",
            "form.between",
            {"low": "0", "high": "10"},
        ),
        (
            {"min_readings": "ten"},
            "min_readings",
            "form.whole_between",
            {"low": "2", "high": "100000"},
        ),
        ({"rubric": "Method | lots"}, "rubric", "assignment.bad_rubric", {"line": 1}),
    ],
)
def test_each_problem_is_kept_by_its_field(change, field, key, params):
    with pytest.raises(FieldProblems) as caught:
        parse_assignment_form({**GOOD, **change})
    problem = caught.value.problems[field]
    assert list(caught.value.problems) == [field]
    assert (problem.key, problem.params) == (key, params)


def test_every_wrong_field_is_refused_at_once_in_the_forms_order():
    change = {"max_attempts": "x", "title": "", "latitude_deg": "91", "earth_rate_deg_h": "0"}
    with pytest.raises(FieldProblems) as caught:
        parse_assignment_form({**GOOD, **change})
    assert list(caught.value.problems) == [
        "title",
        "latitude_deg",
        "earth_rate_deg_h",
        "max_attempts",
    ]


def test_numbers_are_taken_as_people_type_them():
    typed = {**GOOD, "latitude_deg": " 39,9 ", "max_points": "12,5", "azimuth_min_deg": "−0"}
    assignment = parse_assignment_form(typed)
    assert assignment.latitude_deg == 39.9 and assignment.max_points == 12.5
    assert assignment.azimuth_min_deg == 0
