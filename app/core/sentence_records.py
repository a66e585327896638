"""A record of an instrument's ASCII sentences, as a serial terminal captures them: one
``$KIND,field,field,…*CS`` line per output, the way VectorNav's VN-100 and VN-200 send
their asynchronous outputs (``$VNYMR``, ``$VNIMU``, ``$VNQMR``) and NMEA-style devices
theirs.

Each sentence's fields become a record's line, named as the maker's manual names them
(VectorNav's angular rates in rad/s, its temperature in °C), so the record's reader offers
the gyro's axes by name and knows their unit; a sentence of another kind (``$VNERR``, a
reply to a command), a line the capture cut (its first, usually), or one whose checksum
fails (the XOR of its characters between ``$`` and ``*``, two hex digits; or VectorNav's
CRC-16-CCITT, four) is passed over and counted.  The lines keep their numbers.

Reference: VectorNav, *VN-100 User Manual* (UM001), ASCII asynchronous outputs and their
checksum and CRC; NMEA 0183's sentence form.
"""

from __future__ import annotations

import binascii
import re
from collections.abc import Iterable, Iterator
from dataclasses import dataclass

from app.core.text_files import first_texts

# a sentence, perhaps after the time a serial monitor stamped it with (its arrow already
# made a separator: app.core.monitor_stamps)
SENTENCE = re.compile(
    r"(?:(?P<stamp>\d{1,2}:\d{2}:\d{2}(?:[.,]\d+)?)[\t ,;]+)?"
    r"\$(?P<kind>[A-Z][A-Z0-9]{2,9}),(?P<body>[^*$]*)(?:\*(?P<check>[0-9A-Fa-f]{2}|[0-9A-Fa-f]{4}))?"
)
_AXES = ("x", "y", "z")
_MAG = tuple(f"mag_{axis} (gauss)" for axis in _AXES)
_ACCEL = tuple(f"accel_{axis} (m/s^2)" for axis in _AXES)
_GYRO = tuple(f"gyro_{axis} (rad/s)" for axis in _AXES)
# the attitude and quaternion named as orientations, which a record never offers as rates
_ATTITUDE = ("orientation yaw (deg)", "orientation pitch (deg)", "orientation roll (deg)")
# the fields of VectorNav's asynchronous ASCII outputs that carry angular rates
FIELDS: dict[str, tuple[str, ...]] = {
    "VNYMR": (*_ATTITUDE, *_MAG, *_ACCEL, *_GYRO),
    "VNQMR": (
        "quaternion 1",
        "quaternion 2",
        "quaternion 3",
        "quaternion 4",
        *_MAG,
        *_ACCEL,
        *_GYRO,
    ),
    "VNIMU": (*_MAG, *_ACCEL, *_GYRO, "temperature (°C)", "pressure (kPa)"),
}
LOOK_AT = 20  # the first non-blank lines that tell a file of sentences


def is_sentence_record(first_lines: Iterable[str]) -> bool:
    """Whether a file is a capture of ``$KIND,…`` sentences.

    Parameters
    ----------
    first_lines : iterable of str
        The file's first lines.

    Returns
    -------
    bool
        True where most of the first 20 non-blank lines, and at least two, are sentences
        of one kind (the first may be cut: a capture starts mid-sentence).
    """
    texts = first_texts(first_lines, LOOK_AT)
    kinds = [found["kind"] for text in texts if (found := SENTENCE.fullmatch(text))]
    if len(kinds) < 2:
        return False
    most = max(kinds.count(kind) for kind in set(kinds))
    return most >= 2 and 2 * most > len(texts)


def checksum_holds(text: str, check: str) -> bool:
    """Whether a sentence's checksum holds.

    Parameters
    ----------
    text : str
        The sentence, ``$`` to its checksum.
    check : str
        Its checksum: two hex digits, the XOR of the characters between ``$`` and ``*``
        (NMEA 0183's, VectorNav's 8-bit); four, VectorNav's CRC-16-CCITT (polynomial
        0x1021, from 0) of the same characters.

    Returns
    -------
    bool
        True where the characters give the checksum.
    """
    payload = text[1 : text.rindex("*")].encode("ascii", "replace")
    if len(check) == 2:
        value = 0
        for byte in payload:
            value ^= byte
        return value == int(check, 16)
    return binascii.crc_hqx(payload, 0) == int(check, 16)


@dataclass
class Sentences:
    """What a capture's sentences were, filled in as they are read."""

    kind: str | None = None
    header: str | None = None  # the fields' names, comma-separated
    kept: int = 0
    first_line: int | None = None
    last_line: int | None = None
    bad_checksums: int = 0
    first_bad: int | None = None
    passed_over: int = 0  # lines of another kind, or cut
    first_passed: int | None = None

    def notes(self) -> list[dict]:
        """What the reader says of them: the kind read, and the lines left out."""
        said = [
            {
                "key": "allan.note_sentences",
                "params": {"kind": self.kind, "first": self.first_line, "last": self.last_line},
            }
        ]
        if self.bad_checksums:
            said.append(
                {
                    "key": "allan.note_sentences_checksum",
                    "params": {"n": self.bad_checksums, "line": self.first_bad},
                }
            )
        if self.passed_over:
            said.append(
                {
                    "key": "allan.note_sentences_other",
                    "params": {
                        "n": self.passed_over,
                        "line": self.first_passed,
                        "kind": self.kind,
                    },
                }
            )
        return said


def sentence_lines(lines: Iterable[str], sentences: Sentences) -> Iterator[str]:
    """The capture's lines as a record's: each sentence of the first kind its fields,
    comma-separated; any other line blank (so every line keeps its number).

    Parameters
    ----------
    lines : iterable of str
        The file's lines, from its first.
    sentences : Sentences
        Filled in as the lines are read: the kind, its fields' names once the first
        sentence is read, the lines kept and left out.

    Returns
    -------
    iterator of str
        One line for each of the file's.
    """
    for number, raw in enumerate(lines, 1):
        text = raw.strip().lstrip("\ufeff")
        if not text:
            yield "\n"
            continue
        found = SENTENCE.fullmatch(text)
        if found is not None and sentences.kind is None:
            sentences.kind = found["kind"]
        stamped = found is not None and found["stamp"] is not None
        if (
            found is None
            or found["kind"] != sentences.kind
            or (sentences.header is not None and stamped != sentences.header.startswith("time"))
        ):
            sentences.passed_over += 1
            sentences.first_passed = sentences.first_passed or number
            yield "\n"
            continue
        if found["check"] and not checksum_holds(text[found.start("kind") - 1 :], found["check"]):
            sentences.bad_checksums += 1
            sentences.first_bad = sentences.first_bad or number
            yield "\n"
            continue
        if sentences.header is None:
            count = found["body"].count(",") + 1
            names = FIELDS.get(sentences.kind, ())
            if len(names) != count:
                names = tuple(f"field {k}" for k in range(1, count + 1))
            sentences.header = ",".join(("time",) * stamped + names)
        sentences.kept += 1
        sentences.first_line = sentences.first_line or number
        sentences.last_line = number
        yield (f"{found['stamp']}," if stamped else "") + found["body"] + "\n"
