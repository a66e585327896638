"""Issue 31, item 4: no request model of the app turns a string or a boolean into a
number.  Every JSON body model of every route is walked, and each of its numeric fields
(nested models included) is fed "3" and true on its own."""

from __future__ import annotations

import types
import typing

import pytest
from fastapi import params
from fastapi.routing import APIRoute
from pydantic import BaseModel, TypeAdapter, ValidationError

from app.main import create_app
from app.routes import iter_routes

NUMBERS = (int, float)


def body_models(app) -> dict[str, type[BaseModel]]:
    found: dict[str, type[BaseModel]] = {}

    def walk(model: type[BaseModel]) -> None:
        if model.__name__ in found:
            return
        found[model.__name__] = model
        for field in model.model_fields.values():
            for inner in _types(field.annotation):
                if isinstance(inner, type) and issubclass(inner, BaseModel):
                    walk(inner)

    for route in iter_routes(app.routes):
        if isinstance(route, APIRoute) and route.body_field is not None:
            if isinstance(route.body_field.field_info, params.Form):
                continue  # an HTML form is text: its numbers arrive as strings
            for inner in _types(route.body_field.field_info.annotation):
                if isinstance(inner, type) and issubclass(inner, BaseModel):
                    walk(inner)
    return found


def _types(annotation) -> list:
    origin = typing.get_origin(annotation)
    if origin is typing.Annotated:
        return _types(typing.get_args(annotation)[0])
    if origin in (typing.Union, types.UnionType, list, tuple, dict, set):
        return [t for arg in typing.get_args(annotation) for t in _types(arg)]
    return [annotation]


def numeric_fields(model: type[BaseModel]):
    for name, field in model.model_fields.items():
        if any(t in NUMBERS for t in _types(field.annotation)):
            yield name, field


def test_the_walk_finds_the_apps_request_models():
    models = body_models(create_app())
    assert {"Trim", "Turn", "Plane", "TrimIn", "ManualReadings"} <= set(models), sorted(models)


@pytest.mark.parametrize("value", ["3", True])
def test_no_request_model_coerces_strings_or_booleans_into_numbers(value):
    lax, models = [], body_models(create_app())
    assert len(models) >= 10
    for model_name, model in sorted(models.items()):
        strict = bool(model.model_config.get("strict"))
        for name, field in numeric_fields(model):
            annotated = (
                typing.Annotated[field.annotation, *field.metadata]
                if field.metadata
                else (field.annotation)
            )
            try:
                TypeAdapter(annotated).validate_python(value, strict=strict or None)
            except ValidationError:
                continue
            lax.append(f"{model_name}.{name}")
    assert not lax, f"these accept {value!r} as a number: {lax}"


@pytest.mark.one_backend
@pytest.mark.parametrize("trim", ["3", True, 2.5])
def test_a_trim_that_is_not_a_whole_number_is_refused(student_client, trim):
    from tests.factories import new_session, post_json

    session_id = new_session(student_client)
    page = f"/lab/sessions/{session_id}"
    reply = post_json(student_client, f"{page}/trim", {"part": "heading", "position": 1,
                                                        "trim": trim}, page)  # fmt: skip
    assert reply.status_code == 422 and "detail" in reply.json()
