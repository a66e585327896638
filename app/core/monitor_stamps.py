"""A record captured by a serial monitor that stamps each line with the time it arrived:
the Arduino IDE's ("Show timestamp": ``10:00:00.123 -> 10.74``), as students log a gyro
through a microcontroller.  The stamp becomes the record's time column (a logger's clock,
:mod:`app.core.clock_stamps`) and the arrow the line's own separator, so the rest of the
line is read as it would be without the monitor; the lines keep their numbers.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Iterator

from app.core.text_files import first_texts

# "10:00:00.123 -> …": the Arduino IDE's serial monitor with its timestamps shown
STAMPED = re.compile(r"(?P<stamp>\d{1,2}:\d{2}:\d{2}(?:[.,]\d+)?) -> ?(?P<rest>.*)")
LOOK_AT = 20  # the first non-blank lines that tell a stamped capture


def is_stamped_capture(first_lines: Iterable[str]) -> bool:
    """Whether a file is a serial monitor's stamped capture.

    Parameters
    ----------
    first_lines : iterable of str
        The file's first lines.

    Returns
    -------
    bool
        True where most of the first 20 non-blank lines, and at least two, start with a
        time of day and an arrow (``10:00:00.123 -> ``).
    """
    texts = first_texts(first_lines, LOOK_AT)
    stamped = sum(STAMPED.fullmatch(text) is not None for text in texts)
    return stamped >= 2 and 2 * stamped > len(texts)


def unstamped_lines(lines: Iterable[str]) -> Iterator[str]:
    """The capture's lines with each stamp a first column: ``10:00:00.123 -> 10.74`` as
    ``10:00:00.123<TAB>10.74``, joined by the separator the rest of the line uses (a tab,
    a semicolon, or a comma between several values), so that a decimal comma stays one.

    Parameters
    ----------
    lines : iterable of str
        The file's lines.

    Returns
    -------
    iterator of str
        One line for each of the file's: stamped lines rewritten (one stamped with nothing
        after it blank), the others as they are (a header, a line the monitor cut, which
        the reader then judges).
    """
    for raw in lines:
        found = STAMPED.fullmatch(raw.strip().lstrip("\ufeff"))
        if found is None:
            yield raw
            continue
        rest = found["rest"].strip()
        if not rest:  # the device sent an empty line: nothing but its stamp
            yield "\n"
            continue
        yield f"{found['stamp']}{_separator(rest)}{rest}\n"


def _separator(rest: str) -> str:
    """The separator the rest of a line uses, to put between the stamp and it."""
    if "\t" in rest:
        return "\t"
    if ";" in rest:
        return ";"
    if rest.count(",") > 1 or ("," in rest and "." in rest):
        return ","  # several values between commas ("12.3,4.5,6.7")
    if "," in rest or " " not in rest:
        return "\t"  # one value, perhaps with a decimal comma ("12,34")
    return " "  # values between spaces
