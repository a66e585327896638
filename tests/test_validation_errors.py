"""A 422's field problems are in the reader's language (the API's bilingual errors), and
every error type pydantic can raise gets a message, never an exception."""

from __future__ import annotations

import typing

import pytest
from pydantic_core.core_schema import ErrorType

from app.web.validation_errors import field_message, localised_details
from tests.factories import API, new_api_session, token_for


@pytest.mark.parametrize(
    ("error", "english", "chinese"),
    [
        ({"type": "greater_than_equal", "ctx": {"ge": 1}}, "Must be at least 1.", "不能小于 1。"),
        (
            {"type": "less_than_equal", "ctx": {"le": 2147483647}},
            "Must be at most 2147483647.",
            "不能大于 2147483647。",
        ),
        ({"type": "less_than_equal", "ctx": {"le": 90.0}}, "Must be at most 90.", "不能大于 90。"),
        ({"type": "greater_than", "ctx": {"gt": 0.5}}, "Must be more than 0.5.", "必须大于 0.5。"),
        (
            {"type": "literal_error", "ctx": {"expected": "'heading' or 'latitude'"}},
            "Must be one of 'heading' or 'latitude'.",
            "必须是以下之一：'heading'、'latitude'。",
        ),
        (
            {"type": "enum", "ctx": {"expected": "'ccw', 'cw' or 'both'"}},
            "Must be one of 'ccw', 'cw' or 'both'.",
            "必须是以下之一：'ccw'、'cw'、'both'。",
        ),
        (
            {"type": "string_too_long", "ctx": {"max_length": 200}},
            "Too long: at most 200 characters.",
            "太长：最多 200 个字符。",
        ),
        (
            {"type": "too_long", "ctx": {"max_length": 8}, "loc": ("body", "columns")},
            "Too many items: at most 8.",
            "项目太多：最多 8 个。",
        ),
        (  # one position's readings: the grid's column, the API's samples
            {"type": "too_long", "ctx": {"max_length": 100000}, "loc": ("body", "columns", "3")},
            "Too many readings: at most 100000 per position.",
            "读数太多：每个位置最多 100000 个。",
        ),
        (
            {"type": "too_long", "ctx": {"max_length": 100000}, "loc": ("body", "samples")},
            "Too many readings: at most 100000 per position.",
            "读数太多：每个位置最多 100000 个。",
        ),
        ({"type": "missing"}, "Required.", "必填。"),
        ({"type": "int_parsing"}, "Must be a whole number.", "必须是整数。"),
        ({"type": "finite_number"}, "Must be a finite number.", "必须是有限的数值。"),
        # a bound without its limit, and a type the catalogue does not name: the general one
        ({"type": "greater_than_equal"}, "Not a valid value.", "不是有效的值。"),
        ({"type": "no_such_type", "ctx": {"x": 1}}, "Not a valid value.", "不是有效的值。"),
    ],
)
def test_each_problem_in_both_languages(error, english, chinese):
    assert field_message(error, "en") == english
    assert field_message(error, "zh-CN") == chinese


def test_every_pydantic_error_type_has_a_message_in_both_languages():
    types = typing.get_args(ErrorType)
    assert len(types) > 100
    for error_type in types:
        for language in ("en", "zh-CN"):
            for context in ({}, {"ge": 1, "le": 2, "gt": 0, "lt": 3, "expected": "'a' or 'b'"}):
                message = field_message({"type": error_type, "ctx": context}, language)
                assert message and "{" not in message and "validation." not in message, error_type


def test_a_details_list_keeps_the_place_and_the_type():
    details = localised_details(
        [{"loc": ("body", "station", "latitude_deg"), "type": "less_than_equal",
          "ctx": {"le": 90}, "msg": "Input should be less than or equal to 90"}],
        "zh-CN",
    )  # fmt: skip
    assert details == [
        {
            "loc": ["body", "station", "latitude_deg"],
            "type": "less_than_equal",
            "msg": "不能大于 90。",
        }
    ]


@pytest.mark.one_backend  # refused before any database work
def test_the_apis_422_speaks_the_readers_language(client, student):
    auth = token_for(client, "student1")
    chinese = client.get(f"{API}/sessions/-1", headers={**auth, "Accept-Language": "zh-CN"})
    assert chinese.status_code == 422
    assert chinese.json() == {
        "detail": [
            {"loc": ["path", "session_id"], "msg": "不能小于 1。", "type": "greater_than_equal"}
        ]
    }
    english = client.get(f"{API}/sessions/-1", headers=auth).json()["detail"]
    assert english[0]["msg"] == "Must be at least 1."
    session_id = new_api_session(client, auth)
    wrong_part = client.put(
        f"{API}/sessions/{session_id}/sideways/positions/1",
        json={"samples": [1.0] * 10},
        headers={**auth, "Accept-Language": "zh-CN"},
    )
    assert wrong_part.status_code == 422
    assert wrong_part.json()["detail"][0]["msg"] == "必须是以下之一：'heading'、'latitude'。"
    body = client.put(
        f"{API}/sessions/{session_id}/heading/positions/1",
        json={"samples": "many"},
        headers={**auth, "Accept-Language": "zh-CN"},
    ).json()["detail"]
    assert [problem["msg"] for problem in body] == ["必须是列表。"]
