"""How students name the two parts of the lab in a sheet's name or a table's title: part A,
the heading (north finding, the gyro's axis in the horizontal plane: the handout's "表 1
光纤陀螺在水平面内4个位置的采样值"), and part B, the latitude (the axis turned in the
vertical north-south plane: "表 2 … 竖直面内 …")."""

from __future__ import annotations

import re

from app.core.typed_numbers import is_number

PART_WORDS = {
    "heading": (
        "寻北", "水平", "方位", "heading", "horizontal", "north", "parta", "a部分", "部分a",
    ),
    "latitude": ("纬度", "竖直", "垂直", "latitude", "vertical", "partb", "b部分", "部分b"),
}  # fmt: skip
PART_LETTERS = {"heading": "a", "latitude": "b"}  # a name of the letter alone: "A", "B"


def part_named(text: str) -> str | None:
    """The part of the lab a name or a title names, where it names one only.

    Parameters
    ----------
    text : str
        A sheet's name, or a title line's text ("表 2 光纤陀螺在竖直面内…", "Part B").

    Returns
    -------
    str or None
        ``"heading"`` or ``"latitude"``; None where it names neither, or both.
    """
    plain = "".join(text.lower().split())
    named = {
        part
        for part, words in PART_WORDS.items()
        if plain == PART_LETTERS[part] or any(word in plain for word in words)
    }
    return named.pop() if len(named) == 1 else None


_NAMING = re.compile(
    "|".join(re.escape(word) for words in PART_WORDS.values() for word in words) + r"|part\s*[ab]",
    re.IGNORECASE,
)
_LETTER_LINE = re.compile(r"^[ \t]*[ab][ \t,;]*\r?$", re.IGNORECASE | re.MULTILINE)
_CELL_SEPARATORS = re.compile(r"[,;\t]")


def part_titles(text: str) -> list[tuple[int, int, str]]:
    """The lines of a file that title a part's table ("表 2 光纤陀螺在竖直面内4个位置的
    采样值", "Part B", "B"): lines of text without a number in any cell, naming one part.

    Parameters
    ----------
    text : str
        The file's text.

    Returns
    -------
    list of (int, int, str)
        Each title line's start and end in ``text`` and the part it names, in order.
    """
    titles = {}
    candidates = [match.start() for match in _NAMING.finditer(text)]
    candidates += [match.start() for match in _LETTER_LINE.finditer(text)]
    for at in candidates:
        start = text.rfind("\n", 0, at) + 1
        end = text.find("\n", at)
        end = len(text) if end < 0 else end
        if start in titles:
            continue
        cells = [cell.strip() for cell in _CELL_SEPARATORS.split(text[start:end])]
        if any(is_number(cell) for cell in cells if cell):
            continue  # a row of readings, or a header of numbers
        if (part := part_named(" ".join(cells))) is not None:
            titles[start] = (start, end, part)
    return [titles[start] for start in sorted(titles)]


def part_table(text: str, part: str) -> str:
    """A file of both parts' tables, one under the other, each under a title that names
    its part (as the handout prints its tables 1 and 2): ``part``'s table alone, the other
    lines blank so that lines keep their numbers; any other file as it is.

    Parameters
    ----------
    text : str
        The file's text.
    part : {"heading", "latitude"}
        The part whose table is wanted.

    Returns
    -------
    str
        The text, only ``part``'s table in it where it holds both parts' titled tables.
    """
    titles = part_titles(text)
    own = [index for index, (_, _, named) in enumerate(titles) if named == part]
    if len({named for _, _, named in titles}) < 2 or len(own) != 1:
        return text
    begin = titles[own[0]][1]  # after its title line
    end = titles[own[0] + 1][0] if own[0] + 1 < len(titles) else len(text)
    return "\n" * text.count("\n", 0, begin) + text[begin:end] + "\n" * text.count("\n", end)
