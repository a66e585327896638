"""The checks that serial gyros append to their frames.

* ``sum8``: the low byte of the sum of the covered bytes (many teaching FOGs);
* ``xor8``: every covered byte XORed together;
* ``crc16-ccitt``: CRC-16/CCITT-FALSE (also called IBM-3740): polynomial 0x1021, initial
  value 0xFFFF, no reflection, no final XOR; sent big-endian;
* ``crc32-mpeg2``: CRC-32/MPEG-2: polynomial 0x04C11DB7, initial value 0xFFFFFFFF, no
  reflection, no final XOR; sent big-endian (the KVH DSP-1750/1760 "format A" check,
  KVH manual table "CRC Format").

The CRCs come from anycrc (table-driven, in C).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import reduce
from operator import xor

import anycrc

_CRC16_CCITT = anycrc.Model("CRC16-IBM-3740")
_CRC32_MPEG2 = anycrc.Model("CRC32-MPEG-2")


def sum8(data: bytes) -> int:
    """Low byte of the byte sum: ``(Σ bᵢ) mod 256``."""
    return sum(data) & 0xFF


def xor8(data: bytes) -> int:
    """Every byte XORed: ``b₀ ⊕ b₁ ⊕ … ⊕ bₙ``."""
    return reduce(xor, data, 0)


@dataclass(frozen=True)
class Checksum:
    """A frame check: its name, its width in bytes (sent big-endian) and how to compute it."""

    name: str
    size: int
    compute: Callable[[bytes], int]


CHECKSUMS: dict[str, Checksum] = {
    "sum8": Checksum("sum8", 1, sum8),
    "xor8": Checksum("xor8", 1, xor8),
    "crc16-ccitt": Checksum("crc16-ccitt", 2, _CRC16_CCITT.calc),
    "crc32-mpeg2": Checksum("crc32-mpeg2", 4, _CRC32_MPEG2.calc),
}
