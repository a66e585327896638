"""Sample arrays stored compactly: little-endian float64 in BLOB chunks."""

from __future__ import annotations

import numpy as np

CHUNK_SAMPLES = 65_536
DTYPE = np.dtype("<f8")


def pack(values: np.ndarray) -> bytes:
    return np.ascontiguousarray(values, dtype=DTYPE).tobytes()


def unpack(blob: bytes | None) -> np.ndarray:
    if not blob:
        return np.empty(0, dtype=float)
    return np.frombuffer(blob, dtype=DTYPE).astype(float)


def unpack_all(blobs: list[bytes | None]) -> np.ndarray:
    """Several chunks' samples as one array (one copy, whatever the number of chunks)."""
    parts = [np.frombuffer(blob, dtype=DTYPE) for blob in blobs if blob]
    out = np.empty(sum(part.size for part in parts), dtype=float)
    start = 0
    for part in parts:
        out[start : start + part.size] = part
        start += part.size
    return out


def chunks(
    values: np.ndarray,
    times: np.ndarray | None = None,
    temperatures: np.ndarray | None = None,
):
    """(seq, values, times or None, temperatures or None) as bytes, in blocks of at most
    CHUNK_SAMPLES samples."""

    def block(array: np.ndarray | None, start: int, stop: int) -> bytes | None:
        return None if array is None else pack(array[start:stop])

    for seq, start in enumerate(range(0, max(len(values), 1), CHUNK_SAMPLES)):
        stop = start + CHUNK_SAMPLES
        yield (
            seq,
            pack(values[start:stop]),
            block(times, start, stop),
            block(temperatures, start, stop),
        )
