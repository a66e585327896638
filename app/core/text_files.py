"""Text as students and teachers save and type it: files in UTF-8 (with or without a
byte-order mark), UTF-16 from some spreadsheets, or GB18030 from a Chinese-locale Excel --
whole (:func:`decode_text`) or line by line in bounded memory (:func:`text_lines`); a
Chinese input method's full-width forms."""

from __future__ import annotations

import codecs
import io
import re
import unicodedata
from collections.abc import Iterable

from app.core.exceptions import UserError

ENCODINGS = ("utf-8-sig", "gb18030")


def decode_text(data: bytes) -> str:
    """The text of an uploaded file.

    UTF-16 is recognised by its byte-order mark; otherwise UTF-8 is tried first (strict),
    then GB18030, which the simplified-Chinese Excel writes ("另存为 CSV").  GB18030 decodes
    almost any byte string, so a control character other than tab and line ends in the
    result marks the file as binary.

    Parameters
    ----------
    data : bytes
        The file's bytes.

    Returns
    -------
    str
        The text, without a byte-order mark.

    Raises
    ------
    UserError
        ``csv.encoding`` when the bytes are not text in any of these encodings.
    """
    if data.startswith((b"\xff\xfe", b"\xfe\xff")):
        try:
            return data.decode("utf-16")
        except UnicodeDecodeError:
            pass
    for encoding in ENCODINGS:
        try:
            text = data.decode(encoding)
        except UnicodeDecodeError:
            continue
        if not any(ord(ch) < 32 and ch not in "\t\r\n" for ch in text):
            return text
    raise UserError("csv.encoding")


IDEOGRAPHIC_POINT = re.compile(r"(\d)\u3002(?=\d)")


def plain_text(text: str) -> str:
    """Full-width digits, points, commas, signs and spaces as their ASCII forms.

    A Chinese input method in full-width mode types "１０．７４，－０．５"; Unicode's
    compatibility normalisation (NFKC) maps each to its plain form, and leaves Chinese
    characters as they are.  In Chinese punctuation the "." key types "。": between two
    digits it is read as the decimal point ("10。74").  The minus sign "−" (U+2212, what a
    document or a typeset handout writes) is the hyphen-minus a number is read with.

    Parameters
    ----------
    text : str
        Typed, pasted or read from a file.

    Returns
    -------
    str
        ``text`` under NFKC, "−" as "-", "。" between digits a point ("10.74,-0.5");
        ASCII text as it is (no copy).
    """
    if text.isascii():
        return text
    normal = unicodedata.normalize("NFKC", text).replace("\u2212", "-")
    return IDEOGRAPHIC_POINT.sub(r"\1.", normal)


# explicit embeddings, overrides and isolates (LRE RLE PDF LRO RLO, LRI RLI FSI PDI): in a
# name they reorder what follows -- "\u202e" before "student1" shows the username beside it
# as "1tneduts"
BIDI_CONTROLS = re.compile("[\u202a-\u202e\u2066-\u2069]")


def shown_name(text: str) -> str:
    """A person's name as pages show it: surrounding spaces and bidirectional controls
    removed (letters of any script, and the joiners some scripts need, kept).

    Parameters
    ----------
    text : str
        A name typed in a roster or a form, or sent by a sign-in provider.

    Returns
    -------
    str
        The name without explicit bidirectional embeddings, overrides and isolates.
    """
    return BIDI_CONTROLS.sub("", text).strip()


def text_lines(data, chunk: int = 1 << 20) -> Iterable[str]:
    """Lines of a text file's bytes, decoded incrementally: UTF-8 (with or without a BOM),
    UTF-16 by its byte-order mark (a spreadsheet's "Unicode text"), or GB18030 where the
    first block is not UTF-8 (a Chinese-locale Excel's CSV) -- as
    :func:`decode_text` reads a whole file; CRLF or CR line ends.

    Parameters
    ----------
    data : bytes or binary file
        The text's bytes, or a file opened in binary mode.
    chunk : int
        Bytes read at a time.

    Returns
    -------
    iterator of str
        The lines, without their line ends.

    Raises
    ------
    UserError
        ``csv.encoding`` for bytes that are text in none of these encodings.
    """
    buffer = io.BytesIO(data) if isinstance(data, bytes | bytearray) else data
    first = buffer.read(chunk)
    decoder = codecs.getincrementaldecoder(_encoding_of(first))()
    pending, piece = "", first
    while piece:
        try:
            text = decoder.decode(piece)
        except UnicodeDecodeError:
            raise UserError("csv.encoding") from None
        if _CONTROL.search(text):  # no text file holds these: bytes of another kind
            raise UserError("csv.encoding")
        pending += text
        parts = pending.replace("\r\n", "\n").replace("\r", "\n").split("\n")
        pending = parts.pop()
        yield from parts
        piece = buffer.read(chunk)
    if pending:
        yield pending


_CONTROL = re.compile(r"[\x00-\x08\x0b\x0c\x0e-\x1f]")


def _encoding_of(first: bytes) -> str:
    """The encoding of a file from its first block: UTF-16 by its byte-order mark, UTF-8
    where the block decodes as UTF-8 (but for a character cut at its end), else GB18030."""
    if first.startswith((b"\xff\xfe", b"\xfe\xff")):
        return "utf-16"
    try:
        codecs.getincrementaldecoder("utf-8")().decode(first, final=False)
    except UnicodeDecodeError:
        return "gb18030"
    return "utf-8-sig"
