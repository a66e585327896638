"""The simulated gyro's history since switch-on, replayed once per session and kept.

A recording that starts at gyro time t needs the gyro's noise state at t, which the
session's seed defines as its history since switch-on read with no rotation
(``app.lab.sim.SimulatedTake``): t × rate samples to replay -- 216,000 (≈ 60 ms of CPU,
tactical FOG) for a gyro left on for 6 h while it warms up, and again for every position
recorded.  The state at the end of a long replay is kept, per stream, so that the
session's next recording replays only the time since.  It is the same state (a
``GyroStream`` reads any chunking identically), so every process still gives the same
samples for the same take; what is kept only saves work, and is bounded.
"""

from __future__ import annotations

import numpy as np

from app.core.gyro_stream import GyroStream
from app.core.presets import GyroPreset
from app.lab.lru import LruCache

HISTORY_BLOCK = 200_000  # samples replayed at a time (bounded memory)
WORTH_KEEPING = 1_000  # samples (≈ 0.7 ms to replay): a shorter replay costs less than the copies
KEPT_STREAMS = 256  # one per session recording now: a few kB each


# (preset, seed, turn-on bias) → the stream after ``samples_read`` samples of its history,
# never read further (a caller reads from a copy)
KEPT = LruCache(KEPT_STREAMS)


def replay(stream: GyroStream, samples: int) -> None:
    """Read ``samples`` of the history (no rotation), in bounded blocks."""
    while samples > 0:
        block = min(samples, HISTORY_BLOCK)
        stream.read(np.zeros(block))
        samples -= block


def stream_after(
    preset: GyroPreset, seed: int, turn_on_bias_deg_h: float, index: int
) -> GyroStream:
    """The gyro's stream as it is after ``index`` samples of its history since
    switch-on: replayed from the latest state kept for it, or from switch-on; a long
    replay's end state is kept for the next recording."""
    key = (preset, seed, turn_on_bias_deg_h)
    kept = KEPT.get(key) if index >= WORTH_KEEPING else None
    stream = kept.copy() if kept is not None and kept.samples_read <= index else None
    if stream is None:
        stream = GyroStream(preset, seed)
        stream.turn_on_bias_deg_h = turn_on_bias_deg_h  # one power-on value
    replay(stream, index - stream.samples_read)
    if index >= WORTH_KEEPING:
        KEPT.put(key, stream)
        return stream.copy()
    return stream
