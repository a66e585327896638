"""Text as students and teachers save and type it: files in UTF-8 (with or without a
byte-order mark), UTF-16 from some spreadsheets, GB18030 from a Chinese-locale Excel, or
Windows-1252 from a Western Windows program --
whole (:func:`decode_text`) or line by line in bounded memory (:func:`text_lines`), without
the end-of-file marks DOS-era programs leave after the last line (:func:`file_text`); a
Chinese input method's full-width forms."""

from __future__ import annotations

import codecs
import contextlib
import io
import itertools
import re
import unicodedata
from collections.abc import Iterable

from app.core.exceptions import UserError

# Windows-1252 last: a Western Windows program's file ("Rate [°/s]") that is neither; it
# decodes all but five bytes, so the control-character check below still refuses binary
ENCODINGS = ("utf-8-sig", "gb18030", "cp1252")
# What may follow a file's last line and is not text: Ctrl-Z (SUB, 0x1A), DOS's end-of-file
# mark, which DOS-era loggers and terminal captures still write (CP/M padded a file's last
# 128-byte record with them); NUL bytes, the unwritten rest of the space a logger had set
# aside for its file when it lost power (an SD card's preallocated clusters)
END_OF_FILE_MARK = "\x1a\x00"
# control characters no text file has (tab, LF and CR are text): a file that decodes with
# one of them in it is binary
_CONTROL = re.compile(r"[\x00-\x08\x0b\x0c\x0e-\x1f]")


def file_text(text: str) -> str:
    """A file's text without a byte-order mark before it and end-of-file marks after it.

    Parameters
    ----------
    text : str
        A file's whole text (decoded here, or by the browser from the same bytes).

    Returns
    -------
    str
        ``text`` without a leading U+FEFF and trailing Ctrl-Z (0x1A) and NUL characters;
        one in the middle of the text is left to the reader to refuse.
    """
    return text.lstrip("\ufeff").rstrip(END_OF_FILE_MARK)


def first_texts(lines: Iterable[str], count: int) -> list[str]:
    """A file's first ``count`` lines that are not blank, stripped (and a byte-order mark
    with them): what its readers look at to tell its kind.

    Parameters
    ----------
    lines : iterable of str
        The file's lines, from its first (read only as far as needed).
    count : int
        How many to take.

    Returns
    -------
    list of str
        At most ``count`` texts.
    """
    texts = (line.strip().lstrip("\ufeff") for line in lines)
    return list(itertools.islice((text for text in texts if text), count))


def decode_text(data: bytes) -> str:
    """The text of an uploaded file.

    UTF-16 is recognised by its byte-order mark, or without one by the zero bytes of its
    ASCII characters (:func:`utf16_without_mark`); otherwise UTF-8 is tried first (strict),
    then GB18030, which the simplified-Chinese Excel writes ("另存为 CSV"), then
    Windows-1252, a Western Windows program's ("°/s" is no GB18030; "François" and "°C"
    are, but read as Windows-1252: :func:`reads_as_western`).  These decode almost
    any byte string, so a control character other than tab and line ends in the result
    marks the file as binary; Ctrl-Z marks or NUL bytes after the last line (DOS's
    end of file, a logger's unwritten space) are not part of the text.

    Parameters
    ----------
    data : bytes
        The file's bytes.

    Returns
    -------
    str
        The text, without a byte-order mark or end-of-file marks.

    Raises
    ------
    UserError
        ``csv.encoding`` when the bytes are not text in any of these encodings.
    """
    if data.startswith((b"\xff\xfe", b"\xfe\xff")):
        try:
            return data.decode("utf-16").rstrip(END_OF_FILE_MARK)
        except UnicodeDecodeError:
            pass
    unmarked = utf16_without_mark(data)
    if unmarked:
        try:
            text = data.decode(unmarked).rstrip(END_OF_FILE_MARK)
        except UnicodeDecodeError:
            text = "\x00"
        if not _CONTROL.search(text):
            return text
    for encoding in ENCODINGS:
        try:
            text = data.decode(encoding).rstrip(END_OF_FILE_MARK)
        except UnicodeDecodeError:
            continue
        if encoding == "gb18030" and reads_as_western(data, text):
            continue  # "François" in Windows-1252, not "Fran鏾is"
        if not _CONTROL.search(text):  # a regular expression: 0.05 s for 18 MB, not 1 s
            return text
    raise UserError("csv.encoding")


UTF16_SAMPLE = 4096  # bytes looked at for UTF-16's zero bytes


def utf16_without_mark(data: bytes) -> str | None:
    """UTF-16 written without its byte-order mark, told by its zero bytes.

    A program that writes "Unicode" through the Windows API or .NET's ``UnicodeEncoding``
    without a preamble leaves no mark; a table of readings is then almost all ASCII, each
    character's high byte zero: the odd bytes (little-endian) or the even ones
    (big-endian).  Text in a one-byte encoding has no zero bytes at all, a binary file
    (raw floats, an ``.npy``) has them at both, and NUL padding after a logger's last line
    is zero at both too.

    Parameters
    ----------
    data : bytes
        A file's bytes.

    Returns
    -------
    str or None
        ``"utf-16-le"`` or ``"utf-16-be"`` when, in the first 4096 bytes (an even count,
        at least 4), at least half of one parity's bytes are zero and at most one
        in twenty of the other's; None otherwise.
    """
    sample = data[: min(UTF16_SAMPLE, len(data) - len(data) % 2)]
    if len(sample) < 4:
        return None
    half = len(sample) // 2
    even_zeros, odd_zeros = sample[0::2].count(0), sample[1::2].count(0)
    for zeros, others, encoding in (
        (odd_zeros, even_zeros, "utf-16-le"),
        (even_zeros, odd_zeros, "utf-16-be"),
    ):
        if zeros >= 0.5 * half and others <= 0.05 * half:
            return encoding
    return None


_NOT_ASCII = re.compile(r"[^\x00-\x7f]")
# what a Western Windows program writes besides letters: units, signs, typographic quotes
_WESTERN_SIGNS = frozenset("°±µ²³¹·×÷€£¥¢§¶¼½¾’‘‚“”„–—…«»¿¡©®™‰•")


def reads_as_western(data: bytes, gb_text: str) -> bool:
    """Whether bytes that decode as GB18030 are rather Windows-1252: most of their Chinese
    characters lie outside GB2312 and Windows-1252 reads them as letters and common signs.

    A Windows-1252 accented letter and the ASCII letter after it form a valid GB18030
    character ("ç" + "o" in "François": 0xE7 0x6F, "鏾"; "°" + "C": 0xB0 0x43), but
    never one of GB2312's, whose bytes are both ≥ 0xA1 -- the characters a Chinese-locale
    program writes almost always are (a rare one in a name is outnumbered by the rest, and
    a Chinese character read as Windows-1252 is rarely letters only: "喆" is "†´").  Two
    accents in a row can make a GB2312 character ("Þó" in "Þór"); one that runs straight
    into a small ASCII letter counts as outside GB2312 -- a Chinese character seldom does.

    Parameters
    ----------
    data : bytes
        The text's bytes.
    gb_text : str
        ``data`` decoded as GB18030.

    Returns
    -------
    bool
        True when the GB18030 characters outside GB2312 are at least as many as those
        inside it and every character Windows-1252 reads that is not ASCII is a letter or
        a common sign.
    """
    inside = outside = 0
    for found in _NOT_ASCII.finditer(gb_text):
        code = found.group().encode("gb18030")
        if len(code) == 2 and 0xA1 <= code[0] <= 0xF7 and code[1] >= 0xA1:
            if _runs_into_a_small_letter(gb_text, found.start()):
                outside += 1  # "Þó" + "r" in "Þór": two accents make one, inside a word
            else:
                inside += 1
        else:
            outside += 1
    if outside == 0 or outside < inside:  # a tie: "Ñúñez" is one GB2312 character and one not
        return False
    try:
        western = data.decode("cp1252")
    except UnicodeDecodeError:
        return False
    return all(
        char in _WESTERN_SIGNS or unicodedata.category(char).startswith("L")
        for char in set(_NOT_ASCII.findall(western))
    )


def _runs_into_a_small_letter(text: str, index: int) -> bool:
    """Whether the character at ``index`` runs straight into a small ASCII letter, as two
    Windows-1252 accents read as one do inside a word ("Þó" + "r"); a Chinese character
    seldom does ("X轴", "FOG陀螺": a capital before it, not a small letter after)."""
    after = text[index + 1] if index + 1 < len(text) else ""
    return after.isascii() and after.islower()


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
    if len(text) <= PLAIN_BLOCK:
        return _plain(text)
    # a long record with a Chinese header: only its blocks of lines that are not ASCII
    # (normalising 18 MB of a million readings took 0.29 s; a form does not cross a line)
    pieces, start = [], 0
    while start < len(text):
        end = text.find("\n", start + PLAIN_BLOCK) + 1 or len(text)
        piece = text[start:end]
        pieces.append(piece if piece.isascii() else _plain(piece))
        start = end
    return "".join(pieces)


PLAIN_BLOCK = 1 << 16  # characters


def _plain(text: str) -> str:
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
    UTF-16 by its byte-order mark (a spreadsheet's "Unicode text") or without one by its
    zero bytes, GB18030 where the
    first block is not UTF-8 (a Chinese-locale Excel's CSV), Windows-1252 where it is
    neither, each told by the first block that is not ASCII only -- as
    :func:`decode_text` reads a whole file; CRLF or CR line ends; Ctrl-Z marks and NUL
    bytes after the last line dropped.

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
    encoding = _encoding_of(first, final=len(first) < chunk)
    decoder = codecs.getincrementaldecoder(encoding)()
    pending, piece = "", first
    marked = False  # end-of-file marks ended what was read: text after them is not text
    plain = encoding == "utf-8-sig"  # every byte so far ASCII: any of the encodings alike
    while piece:
        try:
            text = decoder.decode(piece)
        except UnicodeDecodeError:
            if not plain:
                raise UserError("csv.encoding") from None
            # the first non-ASCII byte further on than the blocks that chose UTF-8 (a
            # logger's "°C" in Windows-1252 at the end of a long record): the encoding is
            # chosen by this block instead, as if it had been the first
            decoder = codecs.getincrementaldecoder(_encoding_of(piece))()
            plain = False
            try:
                text = decoder.decode(piece)
            except UnicodeDecodeError:
                raise UserError("csv.encoding") from None
        plain = plain and piece.isascii()
        body = text.rstrip(END_OF_FILE_MARK)
        if _CONTROL.search(body) or (marked and body):  # bytes of another kind
            raise UserError("csv.encoding")
        marked = marked or len(body) < len(text)
        pending += body
        # a CR last may be half of a CRLF cut at the block's end: kept for the next block
        cut = len(pending) - pending.endswith("\r")
        parts = _line_ends(pending[:cut]).split("\n")
        pending = parts.pop() + pending[cut:]
        yield from parts
        piece = buffer.read(chunk)
    # half a character last (a logger that lost power mid-write) is dropped, its line cut
    with contextlib.suppress(UnicodeDecodeError):
        pending += decoder.decode(b"", final=True).rstrip(END_OF_FILE_MARK)
    if pending:
        yield from _line_ends(pending).removesuffix("\n").split("\n")


def _line_ends(text: str) -> str:
    """CRLF and a bare CR (an old Mac's line end) as LF."""
    return text.replace("\r\n", "\n").replace("\r", "\n")


def _encoding_of(first: bytes, final: bool = False) -> str:
    """The encoding of a file from its first block: UTF-16 by its byte-order mark or its
    zero bytes (:func:`utf16_without_mark`), UTF-8
    where the block decodes as UTF-8 (but for a character cut at its end), else GB18030
    where it decodes as that and does not read as Windows-1252 (:func:`reads_as_western`),
    else Windows-1252 (:func:`decode_text`'s order).  ``final``: the block is the whole
    file, so a character cut at its end is no character (cp1252's "José" is no GB18030)."""
    if first.startswith((b"\xff\xfe", b"\xfe\xff")):
        return "utf-16"
    unmarked = utf16_without_mark(first)
    if unmarked:
        return unmarked
    for encoding in ("utf-8", "gb18030"):
        try:
            text = codecs.getincrementaldecoder(encoding)().decode(first, final=final)
        except UnicodeDecodeError:
            continue
        if encoding == "gb18030" and reads_as_western(first[: len(text.encode(encoding))], text):
            break
        return "utf-8-sig" if encoding == "utf-8" else encoding
    return "cp1252"
