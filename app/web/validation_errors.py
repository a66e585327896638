"""A 422's field problems in the reader's language.

FastAPI answers a request whose parameters or JSON body do not fit the route's types with
pydantic's errors, each ``{"loc", "msg", "type"}`` with an English ``msg``.  The API keeps
that shape (``loc`` and ``type`` are for programs) and writes ``msg`` from the catalogue
instead, by the error's ``type`` and its limits (``ctx``): "Must be at least 1." /
"不能小于 1。".  A type the catalogue does not name gets its general message.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from typing import Any

from app.web.i18n import translate

# pydantic's error type → (message key, the ``ctx`` entry that fills its ``{limit}``)
MESSAGES: dict[str, tuple[str, str | None]] = {
    "missing": ("validation.missing", None),
    "greater_than_equal": ("validation.at_least", "ge"),
    "greater_than": ("validation.more_than", "gt"),
    "less_than_equal": ("validation.at_most", "le"),
    "less_than": ("validation.less_than", "lt"),
    "int_parsing": ("validation.whole_number", None),
    "int_type": ("validation.whole_number", None),
    "int_from_float": ("validation.whole_number", None),
    "int_parsing_size": ("validation.whole_number", None),
    "float_parsing": ("validation.number", None),
    "float_type": ("validation.number", None),
    "finite_number": ("validation.number", None),
    "bool_parsing": ("validation.true_false", None),
    "bool_type": ("validation.true_false", None),
    "string_type": ("validation.text", None),
    "string_too_short": ("validation.too_short", "min_length"),
    "string_too_long": ("validation.too_long", "max_length"),
    "too_short": ("validation.too_few", "min_length"),
    "too_long": ("validation.too_many", "max_length"),
    "literal_error": ("validation.one_of", None),
    "enum": ("validation.one_of", None),
    "list_type": ("validation.list", None),
    "dict_type": ("validation.object", None),
    "model_type": ("validation.object", None),
    "model_attributes_type": ("validation.object", None),
    "json_invalid": ("validation.json", None),
    "extra_forbidden": ("validation.unknown_field", None),
    "string_pattern_mismatch": ("validation.pattern", None),
    "datetime_parsing": ("validation.datetime", None),
    "datetime_type": ("validation.datetime", None),
    "datetime_from_date_parsing": ("validation.datetime", None),
}
GENERAL = "validation.invalid"
# where one position's readings are: the API's "samples", a column of the typed grid
# ("columns", 3): "too many items" there is too many readings for one position
READINGS_PLACES = (("samples",), ("columns", None))
OPTION_SEPARATORS = re.compile(r", | or ")


def _limit(value: Any) -> str:
    """A bound as a reader writes it: 2147483647, 0.5, 90 (not 2.14748e+09 or 90.0)."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return str(value)
    if isinstance(value, float) and value.is_integer() and abs(value) < 1e15:
        return str(int(value))
    return format(value, ".15g") if isinstance(value, float) else str(value)


def _options(expected: str, language: str) -> str:
    """pydantic's "'en' or 'zh-CN'" in the reader's language ("'en'、'zh-CN'")."""
    if language == "en":
        return expected
    return "、".join(part for part in OPTION_SEPARATORS.split(expected) if part)


def _holds_readings(loc) -> bool:
    """Whether a problem's place is one position's readings (:data:`READINGS_PLACES`)."""
    place = [str(part) for part in loc][1:]  # after "body"
    return any(
        len(place) == len(pattern)
        and all(p is None or p == q for p, q in zip(pattern, place, strict=True))
        for pattern in READINGS_PLACES
    )


def field_message(error: Mapping[str, Any], language: str) -> str:
    """One pydantic error's ``msg`` in ``language``."""
    key, bound = MESSAGES.get(str(error.get("type", "")), (GENERAL, None))
    context = error.get("ctx") or {}
    if bound is not None:
        if bound not in context:
            return translate(GENERAL, language)
        if key == "validation.too_many" and _holds_readings(error.get("loc", ())):
            key = "validation.too_many_readings"
        return translate(key, language, limit=_limit(context[bound]))
    if key == "validation.one_of":
        expected = context.get("expected")
        if not isinstance(expected, str):
            return translate(GENERAL, language)
        return translate(key, language, expected=_options(expected, language))
    return translate(key, language)


def localised_details(errors: Iterable[Mapping[str, Any]], language: str) -> list[dict]:
    """A 422's ``detail``: each problem's place, type and message in ``language``."""
    return [
        {
            "loc": list(error.get("loc", ())),
            "msg": field_message(error, language),
            "type": str(error.get("type", "")),
        }
        for error in errors
    ]
