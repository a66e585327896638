"""JSON has no NaN or infinity: results cross every boundary through :func:`json_safe`."""

from __future__ import annotations

import json
import math

import numpy as np

LARGEST_NUMBER = 1e300  # anything larger is a mistake (and overflows float64 arithmetic)


class UnsafeJson(ValueError):
    """A body that is not plain finite JSON; the message says why."""


def json_safe(value):
    """A copy with NaN/±inf replaced by None and numpy scalars by Python numbers."""
    if isinstance(value, dict):
        return {key: json_safe(item) for key, item in value.items()}
    if isinstance(value, list | tuple):
        return [json_safe(item) for item in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _finite_float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value) or abs(value) > LARGEST_NUMBER:
        raise UnsafeJson(f"The number {text[:40]} is out of range.")
    return value


def _bounded_int(text: str) -> int:
    if len(text.lstrip("-")) > 300:
        raise UnsafeJson(f"The number {text[:40]}… is out of range.")
    return int(text)


def _no_constant(name: str):
    raise UnsafeJson(f"{name} is not a number JSON allows: send finite numbers only.")


def loads_finite(body: bytes | str):
    """Parse JSON that holds finite numbers only: NaN, Infinity, 1e309 and 10**400 are
    refused with :class:`UnsafeJson`, and so is nesting too deep to parse."""
    try:
        return json.loads(
            body,
            parse_float=_finite_float,
            parse_int=_bounded_int,
            parse_constant=_no_constant,
        )
    except RecursionError:
        raise UnsafeJson("The JSON is nested too deeply.") from None
    except (json.JSONDecodeError, UnicodeDecodeError):
        raise UnsafeJson("The body is not valid JSON.") from None
