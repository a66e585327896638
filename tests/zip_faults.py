"""Zips the ``zipfile`` module cannot read, made from good ones by rewriting their headers
(PKWARE's APPNOTE.TXT: local header ``PK\\x03\\x04``, central directory ``PK\\x01\\x02``):
a newer "version needed to extract", another compression method (9: Deflate64, as 7-Zip
offers it), a member marked encrypted (general-purpose flag bit 0)."""

from __future__ import annotations

import struct

LOCAL, CENTRAL = b"PK\x03\x04", b"PK\x01\x02"
# field offsets in each header: (version needed, flags, method)
OFFSETS = {LOCAL: (4, 6, 8), CENTRAL: (6, 8, 10)}


def zip_patched(
    data: bytes, *, version: int | None = None, method: int | None = None, encrypted: bool = False
) -> bytes:
    """``data`` (a zip) with every member's headers rewritten as asked."""
    patched = bytearray(data)
    for signature, (at_version, at_flags, at_method) in OFFSETS.items():
        start = 0
        while (start := patched.find(signature, start)) != -1:
            if version is not None:
                patched[start + at_version : start + at_version + 2] = struct.pack("<H", version)
            if method is not None:
                patched[start + at_method : start + at_method + 2] = struct.pack("<H", method)
            if encrypted:
                (flags,) = struct.unpack_from("<H", patched, start + at_flags)
                struct.pack_into("<H", patched, start + at_flags, flags | 0x1)
            start += 4
    return bytes(patched)
