"""The spike count of a position (|x − median| > 6 robust σ): the fast path for long records
gives exactly the direct count, on records the simulator did not make."""

from __future__ import annotations

import numpy as np
import pytest

from app.core.record_checks import _certainly_none, count_spikes


def direct_count(values: np.ndarray, limit: float = 6.0) -> int:
    median = np.median(values)
    deviation = np.abs(values - median)
    sigma = 1.4826 * np.median(deviation)
    return int(np.sum(deviation > limit * sigma)) if sigma > 0 else 0


def records():
    rng = np.random.default_rng(20261125)
    n = 70_001
    yield "white", rng.normal(10.0, 0.1, n)
    yield "white, even length", rng.normal(-3.0, 2.0, n + 1)
    spiky = rng.normal(0.0, 1.0, n)
    spiky[rng.choice(n, 7, replace=False)] += 50.0
    yield "seven spikes", spiky
    edge = rng.normal(0.0, 1.0, n)
    edge[5] = 6.05  # just past the limit
    edge[6] = -5.95  # just inside
    yield "at the limit", edge
    yield "heavy tails (Cauchy)", rng.standard_cauchy(n)
    yield "quantised", np.round(rng.normal(0.0, 0.3, n) / 0.25) * 0.25
    yield "constant", np.full(n, 4.2)
    mostly_constant = np.full(n, 1.0)
    mostly_constant[: n // 3] = rng.normal(1.0, 1.0, n // 3)
    yield "more than half identical", mostly_constant
    yield "random walk", np.cumsum(rng.normal(0.0, 1.0, n))
    periodic = np.tile([0.0, 0.0, 0.0, 100.0], n // 4 + 1)[:n]
    yield "periodic with the sample's stride", periodic
    yield "a step", np.r_[np.zeros(n // 2), np.ones(n - n // 2)] + rng.normal(0, 1e-3, n)
    yield "short", rng.normal(0.0, 1.0, 50)
    # a position's usual record (≤ 4,096 readings: the median by a sort), odd and even
    for count in (2, 3, 10, 11, 600, 4096, 4097):
        few = np.round(rng.normal(11.0, 0.05, count), 2)
        few[count // 2] += 1.0  # a spike, once the record is long enough to show one
        yield f"{count} typed readings", few
    yield "ten, one of them NaN", np.r_[rng.normal(0.0, 1.0, 9), np.nan]


@pytest.mark.parametrize(("name", "values"), list(records()), ids=[n for n, _ in records()])
def test_the_spike_count_equals_the_direct_count(name, values):
    assert count_spikes(values) == direct_count(values)


def test_the_fast_path_is_taken_on_clean_long_records_and_never_where_there_are_spikes():
    rng = np.random.default_rng(7)
    clean = [_certainly_none(rng.normal(0.0, 1.0, 100_000), 6.0) for _ in range(40)]
    assert sum(clean) >= 36  # a clean normal record's largest reading is ≈ 4.4 σ
    spiky = rng.normal(0.0, 1.0, 100_000)
    spiky[123] = 6.5
    assert not _certainly_none(spiky, 6.0)
    assert count_spikes(spiky) == direct_count(spiky) == 1
