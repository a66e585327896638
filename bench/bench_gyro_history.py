"""Starting a simulated recording after the gyro has been on a while (issue 32).

    .venv/bin/python bench/bench_gyro_history.py

A recording at gyro time t needs the noise state at t: the history since switch-on,
t × 10 samples for the tactical FOG.  For a session whose gyro is warming up (minutes to
hours), each of its eight positions starts a little later than the last: from switch-on
every time, against from the state kept after the previous one (``app.lab.gyro_history``).
Thread CPU per take start, median of five sessions.
"""

from __future__ import annotations

import statistics
import time

from app.lab import gyro_history
from app.lab.sim import SimulatedTake
from app.models import LabSession

GAP_S = 90.0  # a position's dwell and the turn before the next


def lab(seed: int) -> LabSession:
    return LabSession(
        owner_id=1,
        title="bench",
        latitude_deg=39.93,
        earth_rate_deg_h=15.04,
        simulator_preset="tactical-fog",
        sim_seed=seed,
        sim_azimuth_deg=10.0,
    )


def eight_positions_ms(seed: int, on_for_s: float, keep: bool) -> float:
    """Thread CPU (ms) of starting eight recordings, GAP_S apart, after ``on_for_s``."""
    gyro_history.KEPT.clear()
    session = lab(seed)
    began = time.thread_time()
    for k in range(8):
        if not keep:
            gyro_history.KEPT.clear()
        SimulatedTake(session, "heading", 1, start_s=on_for_s + k * GAP_S)
    return (time.thread_time() - began) * 1000


def main() -> None:
    SimulatedTake(lab(0), "heading", 1, start_s=10.0)  # imports and first-use costs
    print("gyro on before the first position | from switch-on (ms, 8 takes) | kept (ms)")
    for minutes in (5, 30, 120, 300):
        scratch = statistics.median(eight_positions_ms(s, minutes * 60, False) for s in range(5))
        kept = statistics.median(eight_positions_ms(s, minutes * 60, True) for s in range(5))
        print(f"{minutes:>5} min | {scratch:8.1f} | {kept:8.1f}")
    gyro_history.KEPT.clear()


if __name__ == "__main__":
    main()
