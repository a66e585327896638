"""The data evidence on readings it did not make: the tests' own noise generator (white
and Kasdin flicker noise, tests/noise_sources.py), the handout's tables, and closed forms.
bench/bench_evidence.py measures the rates on whole simulated classes."""

from __future__ import annotations

import numpy as np
import pytest

from app.core.data_evidence import (
    class_copies,
    last_digits,
    off_grid,
    part_evidence,
    recording_times,
    too_close,
)
from app.core.noise_model import GyroNoise
from app.core.reading_moments import reading_moments
from tests.factories import handout
from tests.noise_sources import static_record

NOISE = GyroNoise(arw_deg_rt_h=0.02, bias_instability_deg_h=0.05)
RATE = 10.0


def honest_part(seed: int, count: int = 300) -> list[np.ndarray]:
    record = static_record(4 * count / RATE / 3600.0, RATE, arw=0.02, flicker=0.05, seed=seed)
    return [record[k * count : (k + 1) * count] + 11.0 * np.cos(k * np.pi / 2) for k in range(4)]


def test_one_readings_variance_is_the_white_density_times_the_rate():
    """White noise alone: σ₁² = (60N)²·f, no correlation between readings."""
    one, rho, mean = reading_moments(GyroNoise(arw_deg_rt_h=0.02), RATE, 100)
    assert one == pytest.approx((60 * 0.02) ** 2 * RATE, rel=1e-9)
    assert rho == pytest.approx(0.0, abs=1e-12)
    assert mean == pytest.approx(one / 100, rel=1e-9)


def test_honest_independent_records_are_not_flagged():
    flagged = [
        e.check
        for seed in range(40)
        for e in part_evidence("heading", honest_part(seed), False, NOISE, RATE)
    ]
    assert flagged == []


def test_a_device_faster_than_the_gyros_record_is_judged_at_its_own_rate():
    """The station's gyro characterised at 10 Hz; a group sends it at 1 kHz with its times
    (honest white noise of the same N, independent of GyroLab's simulator): each reading
    is 10× noisier, as a 1 ms average is.  Judged at the readings' own rate only the time
    step is said -- before, "scatter ten times the gyro's" too.  Without times, or logged
    sparsely (single 10 Hz samples 10 s apart), the gyro's rate is the one."""
    from app.core.data_evidence import readings_rate_hz

    fast = 1000.0
    record = static_record(4 * 2000 / fast / 3600.0, fast, arw=0.02, seed=4)
    part = [record[k * 2000 : (k + 1) * 2000] + 11.0 * np.cos(k * np.pi / 2) for k in range(4)]
    times = [100.0 * k + np.arange(2000) / fast for k in range(4)]
    white = GyroNoise(arw_deg_rt_h=0.02)
    found = part_evidence("heading", part, False, white, RATE, times=times)
    assert [e.check for e in found] == ["time_step"]
    assert readings_rate_hz(times, RATE) == pytest.approx(fast)
    untimed = part_evidence("heading", part, False, white, RATE)
    assert [e.check for e in untimed] == ["scatter_high"]
    assert untimed[0].numbers["ratio"] == pytest.approx(10.0, rel=0.05)
    sparse = [10.0 * np.arange(30) + 1000.0 * k for k in range(4)]
    assert readings_rate_hz(sparse, RATE) == RATE
    assert readings_rate_hz([times[0], None], RATE) == RATE


def test_smoothed_and_invented_readings_are_found():
    kernel = np.ones(5) / 5
    smoothed = [np.convolve(v, kernel, mode="valid") for v in honest_part(1)]
    checks = {e.check for e in part_evidence("heading", smoothed, False, NOISE, RATE)}
    assert "smooth" in checks and "scatter_low" in checks
    noisier = [v + np.random.default_rng(2).normal(0, 10, v.size) for v in honest_part(2)]
    assert {e.check for e in part_evidence("heading", noisier, False, NOISE, RATE)} == {
        "scatter_high"
    }


def test_a_preferred_last_digit_is_found_only_where_digits_should_be_uniform():
    rng = np.random.default_rng(3)
    honest = [np.round(11 + rng.normal(0, 0.5, 15), 2) for _ in range(4)]
    assert last_digits("heading", honest, 0.5) == []
    leaning = [np.round(v * 20) / 20 for v in honest]  # every reading ends in 0 or 5
    found = last_digits("heading", leaning, 0.5)
    assert found and found[0].check == "digits" and found[0].numbers["digit"] in (0, 5)
    assert last_digits("heading", leaning, 0.5, own_step=0.1) == []  # the gyro's own grid


def test_readings_between_the_simulated_gyros_steps_are_found():
    on = [np.round(np.random.default_rng(4).normal(11, 0.2, 12) / 0.1) * 0.1 for _ in range(4)]
    assert off_grid("heading", on, 0.1) == []
    off = [np.round(v + 0.03, 2) for v in on]
    assert off_grid("heading", off, 0.1)[0].numbers["share"] == 1.0


def test_a_part_copied_with_offsets_or_reordered_is_found_and_honest_parts_are_not():
    parts = {f"g{seed}": honest_part(seed, 30) for seed in range(20)}
    copied = [v + 0.37 for v in parts["g3"]]
    shuffled = [np.random.default_rng(5).permutation(v) - 1.1 for v in parts["g7"]]
    takes = [(group, "heading", positions) for group, positions in parts.items()]
    takes += [("copier", "heading", copied), ("shuffler", "heading", shuffled)]
    found = class_copies(takes)
    assert found["copier"][0].numbers["others"] == ["g3"]
    assert found["shuffler"][0].numbers["others"] == ["g7"]
    assert set(found) == {"copier", "g3", "shuffler", "g7"}


def test_the_handout_retyped_is_found():
    table = handout("handout_horizontal.csv")
    positions = [np.array(table[k]) for k in sorted(table)]
    found = part_evidence("heading", positions, True, NOISE, RATE)
    assert any(e.check == "handout" and "heading-1" in e.numbers["columns"] for e in found)
    shifted = [v + 0.2 for v in positions]  # with an offset too
    assert any(e.check == "handout" for e in part_evidence("heading", shifted, True, NOISE, RATE))


def test_a_result_far_closer_than_its_sigma_is_found():
    assert too_close("heading", 0.0001, 0.1)[0].numbers["z"] == 0.001
    assert too_close("heading", 0.01, 0.1) == []
    assert too_close("heading", None, 0.1) == []


def test_reading_times_out_of_order_or_at_another_step_are_found():
    rng = np.random.default_rng(11)
    rate = 10.0
    # an instrument clock at 10 Hz with 1 ms of jitter: consistent
    honest = [np.arange(600) / rate + rng.normal(0.0, 1e-3, 600) + 300.0 * k for k in range(4)]
    assert recording_times("heading", honest, rate) == []
    assert recording_times("heading", [None, None, None, None], rate) == []
    # one reading a second at a 10 Hz station: another output setting, or timed by hand
    (slow,) = recording_times("heading", [np.arange(60.0) + 100 * k for k in range(4)], rate)
    assert slow.check == "time_step" and slow.numbers == {"step": 1.0, "expected": 0.1}
    # 4 % off is within the tolerance of a clock
    assert recording_times("heading", [np.arange(60) * 0.104 for _ in range(4)], rate) == []
    # two files joined in the wrong order: the clock jumps back once
    joined = np.r_[np.arange(30, 60), np.arange(30)] / rate
    (backwards,) = recording_times("latitude", [joined, *honest[1:]], rate)
    assert backwards.check == "time_order" and backwards.numbers == {"n": 1}
    assert backwards.part == "latitude"
    # repeated time stamps (typed by hand to the second) are out of order too
    stamped = [np.repeat(np.arange(10.0), 10) / 10 for _ in range(4)]
    assert {e.check for e in recording_times("heading", stamped, rate)} == {"time_order"}


@pytest.mark.parametrize("count", [1, 30, 512, 513, 3000])
def test_the_typed_step_is_the_fewest_decimals_that_write_every_reading(count):
    """Readings written to d decimals (as text, then parsed) give 10⁻ᵈ whether typed_step
    checks every d at once (≤ 512 readings) or one at a time; full floats give None."""
    from app.core.data_copies import typed_step

    rng = np.random.default_rng(count)
    for decimals in range(7):
        raw = rng.normal(-11.0, 0.05, count)
        written = np.array([float(f"{x:.{decimals}f}") for x in raw])
        # the fewest decimals whose text gives back every reading (a few may end in 0)
        fewer = next(d for d in range(7) if all(float(f"{x:.{d}f}") == x for x in written))
        assert typed_step(written) == pytest.approx(10.0**-fewer)
    assert typed_step(rng.normal(-11.0, 0.05, count)) is None
    assert typed_step(np.full(count, np.nan)) is None
