"""JSON has no NaN or infinity: results cross every boundary through :func:`json_safe`."""

from __future__ import annotations

import json
import math

import numpy as np

from app.core.exceptions import UserError

LARGEST_NUMBER = 1e300  # anything larger is a mistake (and overflows float64 arithmetic)


def json_safe(value):
    """A copy that JSON can carry: NaN and ±inf become None, numpy scalars Python numbers.

    Parameters
    ----------
    value : object
        Nested dicts, lists and tuples of numbers, strings and None.

    Returns
    -------
    object
        The same structure, safe for ``json.dumps(..., allow_nan=False)``.
    """
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
        raise UserError("json.out_of_range", number=text[:40])
    return value


def _bounded_int(text: str) -> int:
    if len(text.lstrip("-")) > 300:
        raise UserError("json.out_of_range", number=text[:40] + "…")
    return int(text)


def _no_constant(name: str):
    raise UserError("json.constant", name=name)


def loads_finite(body: bytes | str):
    """Parse JSON that holds finite numbers only.

    NaN, Infinity, 1e309 and 10**400 are refused, and so is nesting too deep to parse.

    Parameters
    ----------
    body : bytes or str
        The JSON text.

    Returns
    -------
    object
        The parsed value.

    Raises
    ------
    UserError
        ``json.out_of_range``, ``json.constant``, ``json.too_deep`` or ``json.invalid``.
    """
    try:
        return json.loads(
            body,
            parse_float=_finite_float,
            parse_int=_bounded_int,
            parse_constant=_no_constant,
        )
    except RecursionError:
        raise UserError("json.too_deep") from None
    except (json.JSONDecodeError, UnicodeDecodeError):
        raise UserError("json.invalid") from None
