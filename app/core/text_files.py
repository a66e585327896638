"""Text files as students and teachers save them: UTF-8 (with or without a byte-order
mark), UTF-16 from some spreadsheets, or GB18030 from a Chinese-locale Excel."""

from __future__ import annotations

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
