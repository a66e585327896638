"""Numbers as people and instruments write them: a plain decimal in a file, and a number
typed in a form (a decimal comma, a minus sign, a Chinese input method's full-width forms).
"""

from __future__ import annotations

import math
import re

from app.core.text_files import plain_text

# A plain decimal number: what a spreadsheet or a gyro writes.  Python's float() also takes
# "1_000", "nan", "infinity" and " 1 " -- none of them a reading.
DECIMAL = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")


class NumberOutOfRange(ValueError):
    """A well-formed number too large for a float (e.g. 1e400)."""


def parse_decimal(text: str) -> float:
    """``text`` as a float when it is a plain decimal number.

    Python's ``float`` also takes "1_000", "nan", "infinity" and " 1 " -- none of them a
    reading.

    Parameters
    ----------
    text : str
        A cell of a file or a form.

    Returns
    -------
    float
        The number.

    Raises
    ------
    ValueError
        When it is not a plain decimal number (:class:`NumberOutOfRange` when it is one
        but overflows).
    """
    if not DECIMAL.fullmatch(text):
        raise ValueError(f"not a number: {text[:40]!r}")
    value = float(text)
    if not math.isfinite(value):
        raise NumberOutOfRange(f"out of range: {text[:40]!r}")
    return value


def parse_typed_number(text: str) -> float:
    """One number typed in a form field, as people write it.

    Surrounding spaces, one decimal comma ("12,5" → 12.5), the minus sign "−" (U+2212)
    and a Chinese input method's full-width forms ("－１２．５") are taken; the rest is
    :func:`parse_decimal`'s plain decimal.

    Parameters
    ----------
    text : str
        What was typed in the field.

    Returns
    -------
    float
        The number.

    Raises
    ------
    ValueError
        When it is not one number (as :func:`parse_decimal`).
    """
    text = plain_text(text).strip().replace("\u2212", "-")
    if "," in text and "." not in text and text.count(",") == 1:
        text = text.replace(",", ".")
    return parse_decimal(text)


def is_number(text: str) -> bool:
    """Whether ``text`` is a plain decimal number (:func:`parse_decimal`).

    Parameters
    ----------
    text : str
        A cell.

    Returns
    -------
    bool
        True for a plain decimal, one too large for a float included (reported when it is
        read).
    """
    try:
        parse_decimal(text)
    except NumberOutOfRange:
        return True  # a number, just too large: reported when it is read
    except ValueError:
        return False
    return True
