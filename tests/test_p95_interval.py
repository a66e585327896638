"""bench/p95_interval.py: how well one load-test run knows its own p95."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import binom

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))

import p95_interval  # noqa: E402  (bench/)
import queue_model  # noqa: E402
import queue_sim  # noqa: E402

from tests.test_queue_model import costs  # noqa: E402


def test_the_medians_interval_of_a_hundred_values_is_the_textbooks():
    """The distribution-free 95 % interval of the median of 100 values is X_(40) to X_(61)
    (the standard table; coverage 0.965)."""
    assert p95_interval.order_statistic_ranks(100, 0.5, 0.95) == (40, 61)
    coverage = binom.cdf(60, 100, 0.5) - binom.cdf(39, 100, 0.5)
    assert coverage == pytest.approx(0.965, abs=0.001)


def test_too_few_requests_cannot_bound_the_p95_from_above():
    """14 requests (a teacher's dashboard in one run) all fall below the p95 with chance
    0.95¹⁴ ≈ 0.49: no request is a 90 % upper bound; 59 is the fewest that bound it."""
    assert p95_interval.order_statistic_ranks(14)[1] is None
    assert p95_interval.order_statistic_ranks(58)[1] is None  # 0.95⁵⁸ = 0.051
    assert p95_interval.order_statistic_ranks(59)[1] == 59  # 0.95⁵⁹ = 0.0485 ≤ 0.05
    low, high = p95_interval.quantile_interval(np.arange(14.0))
    assert math.isfinite(low) and high == math.inf


def test_the_interval_holds_the_true_p95_as_often_as_it_says():
    """Samples of 120 from an exponential distribution (drawn here, not by the model):
    the interval holds the true p95, −ln 0.05, in ≥ 90 % of 4000 samples, and as often as
    the binomial sum says it should, within the Monte Carlo's scatter."""
    rng = np.random.default_rng(7)
    truth = -math.log(0.05)
    samples = rng.exponential(1.0, size=(4000, 120))
    held = np.mean(
        [low <= truth <= high for low, high in map(p95_interval.quantile_interval, samples)]
    )
    low_rank, high_rank = p95_interval.order_statistic_ranks(120)
    exact = binom.cdf(high_rank - 1, 120, 0.95) - binom.cdf(low_rank - 1, 120, 0.95)
    assert exact >= 0.90
    assert held == pytest.approx(exact, abs=4 * math.sqrt(exact * (1 - exact) / 4000))


def test_a_runs_intervals_are_read_from_the_load_generators_times(tmp_path):
    """``GYROLAB_BENCH_CLIENT_TIMES``: each request's send and answer times; per route
    the count, the p95 as the load test computes it and its interval."""
    lines = [f"POST /lab/sessions/{i % 7}/turn {i}.0 {i}.{i % 50 + 10:03d}" for i in range(100)]
    lines.append("GET /login 200.0 200.004")
    path = tmp_path / "client.txt"
    path.write_text("\n".join(lines) + "\nGET /lab cut\n")
    intervals = p95_interval.run_intervals(path)
    count, p95, low, high = intervals["POST /lab/sessions/{id}/turn"]
    turns = np.array([(i % 50 + 10) for i in range(100)], dtype=float)
    assert count == 100 and p95 == pytest.approx(np.percentile(turns, 95), abs=1e-6)
    assert low <= p95 <= high
    assert intervals["GET /login"][:2] == (1, pytest.approx(4.0, abs=1e-6))
    assert "GET /lab" not in intervals  # a line cut short


def test_the_counts_say_inside_within_ten_per_cent_and_resolved(capsys):
    intervals = {
        "GET /lab": (120, 100.0, 95.0, 108.0),  # resolved: −5 / +8 %
        "POST /login": (60, 50.0, 40.0, 80.0),  # not: −20 / +60 %
        "GET dashboard (teacher)": (14, 80.0, 40.0, math.inf),
    }
    predicted = {"GET /lab": 109.0, "POST /login": 70.0, "GET dashboard (teacher)": 85.0}
    rows = p95_interval.compare(predicted, intervals)
    counts = p95_interval.tally(rows)
    assert counts["all"] == {"count": 3, "inside": 2, "within 10 %": 2, "resolved": 1}
    assert counts["GET /lab"]["inside"] == 0 and counts["GET /lab"]["within 10 %"] == 1
    out = capsys.readouterr().out
    assert "-50 / — %" in out  # the unbounded side shown as such
    p95_interval.print_ceiling(rows, rows)
    assert "  2 / 3" in capsys.readouterr().out


def test_an_exact_model_scored_against_its_own_runs_is_within_ten_per_cent_more_often():
    """``queue_model.py --model-as-run``: seeds the prediction did not use, each scored as
    a run. The prediction from the other seeds is inside those runs' intervals, and within
    10 % of their p95, far more often than the same prediction made 40 % too fast (40 %
    too slow is still inside most intervals of 20 students: their upper ends are the
    slowest requests, or unbounded)."""
    runs = [queue_sim.simulate(costs(), 20, 1, 2.0, teacher=False, seed=s) for s in range(6)]
    predicted = queue_model.combine(runs[:3])["p95"]
    held_out = []
    for run in runs[3:]:
        latencies = {route: np.array(v) * 1000 for route, v in run["latencies"].items()}
        held_out.append(p95_interval.intervals_of(latencies))
    right = p95_interval.tally(
        [row for run in held_out for row in p95_interval.score(predicted, run)]
    )
    fast = {route: 0.6 * value for route, value in predicted.items()}
    wrong = p95_interval.tally([row for run in held_out for row in p95_interval.score(fast, run)])
    assert right["all"]["count"] == wrong["all"]["count"] > 0
    assert right["all"]["inside"] > 2 * wrong["all"]["inside"]
    assert right["all"]["within 10 %"] > 2 * wrong["all"]["within 10 %"]


def test_runs_pooled_know_their_p95_about_root_k_better(capsys):
    """``queue_model.py --pooled``: eight runs' requests taken together (lognormal draws
    made here, not by the model) bound the true p95, exp(μ + 1.645 σ), by an interval about
    √8 narrower than one run's, and the pooled prediction is the p95 of every seed of every
    run's model; each unused seed, pooled over the runs, is scored as one run."""
    rng = np.random.default_rng(11)
    mu, sigma, route = 4.0, 0.5, "GET /lab"
    truth = math.exp(mu + sigma * 1.6448536)
    pool, singles = queue_model.Pool(), []
    for _ in range(8):
        seen = {route: rng.lognormal(mu, sigma, 60)}
        pool.add_run(seen, {route: rng.lognormal(mu, sigma, 600)})
        for index in range(3):
            pool.add_model_run(index, {route: rng.lognormal(mu, sigma, 60)})
        _, p95, low, high = p95_interval.intervals_of(seen)[route]
        singles.append((high - low) / p95)
    assert pool.runs == 8
    assert pool.predicted()[route] == pytest.approx(truth, rel=0.06)
    rows, exact = pool.compare()
    ((_, (count, p95, low, high), _, _, _),) = rows
    assert count == 480 and low <= truth <= high
    assert (high - low) / p95 < 0.5 * float(np.median(singles))
    assert len(exact) == 3 and all(row[1][0] == 480 for row in exact)
    assert "an exact model" in capsys.readouterr().out


def test_the_prediction_keeps_every_seeds_requests_for_pooling():
    runs = [queue_sim.simulate(costs(), 4, 1, 2.0, teacher=False, seed=s) for s in range(3)]
    pooled = queue_model.combine(runs)["pooled"]
    for route, values in pooled.items():
        assert len(values) == sum(len(run["latencies"][route]) for run in runs)
        assert values[0] == pytest.approx(runs[0]["latencies"][route][0] * 1000)


def test_a_routes_requests_by_when_they_were_sent_model_beside_run(tmp_path, capsys):
    """``--by-time``: the run's requests are placed on the class's clock (its first request
    sent at the earliest student's start in the ramp), and each 2 s window shows how many
    requests a run had and their p50 / p95, the model's seeds averaged."""
    import random

    earliest = min(random.Random(index).uniform(0, 3.0) for index in range(4))
    clock = 1000.0  # perf_counter's origin is arbitrary
    lines = [f"GET /login {clock:.6f} {clock + 0.004:.6f}"]
    lines += [
        f"POST /lab/sessions/1/turn {clock + t:.6f} {clock + t + latency:.6f}"
        for t, latency in ((0.5, 0.020), (1.0, 0.030), (2.5, 0.400), (3.0, 0.500))
    ]
    path = tmp_path / "client.txt"
    path.write_text("\n".join(lines) + "\n")
    sent = queue_model.sent_from_start(p95_interval.client_requests(path), 4)
    turn = "POST /lab/sessions/{id}/turn"
    assert sent["GET /login"][0, 0] == pytest.approx(earliest)
    assert sent[turn][:, 0] == pytest.approx(earliest + np.array([0.5, 1.0, 2.5, 3.0]))
    model = [
        [(turn, earliest + 0.5, 0.010), (turn, earliest + 2.5, 0.300), ("GET /lab", 0.1, 1.0)],
        [(turn, earliest + 0.6, 0.012)],
    ]
    queue_model.compare_by_time(turn, model, sent)
    lines = capsys.readouterr().out.splitlines()
    assert "p95 over all" in lines[0]
    # 0-2 s: the model 1 a run (2 over 2 seeds), the run 2 requests
    assert lines[1].split("|")[0].split()[2] == "1"
    assert lines[1].split("|")[1].split()[0] == "2"


def test_the_gaps_between_a_routes_requests_are_counted_per_seed_and_against_chance(capsys):
    """``--by-time`` also says how close together a route's requests were sent in each part
    of the class: turns every 30 ms in each of the model's two seeds (interleaved, the
    seeds would make 15 ms gaps: each seed is counted alone), every 8 ms in the run."""
    assert queue_model.close_gaps([0.0, 0.008, 0.016, 0.030]).tolist() == pytest.approx(
        [0.0, 2 / 3, 1.0]
    )
    assert queue_model.close_gaps([1.0]) is None
    turn = "POST /lab/sessions/{id}/turn"
    model = [[(turn, 6.0 + 0.030 * k + offset, 0.01) for k in range(20)] for offset in (0, 0.015)]
    sent = {turn: np.array([(6.0 + 0.008 * k, 0.01) for k in range(20)])}
    queue_model.compare_by_time(turn, model, sent)
    lines = capsys.readouterr().out.splitlines()
    (part_a,) = [line for line in lines if line.split()[:2] == ["part", "A"]]
    model_cells, measured_cells, random_cells = part_a.split("|")
    assert model_cells.split()[2:] == ["0", "/", "0", "/", "0"]
    assert measured_cells.split() == ["0", "/", "100", "/", "100"]
    rate = 19 / (0.008 * 19)  # 125 a second
    assert random_cells.split()[0] == f"{100 * (1 - np.exp(-rate * 0.005)):.0f}"


def test_the_runs_own_spread_is_each_routes_p95_largest_over_smallest():
    """Three runs of a route whose p95s are 100, 105 and 150 ms: 1.5× apart, and the third
    is more than 10 % from the runs' median (105); a route whose runs agree within 10 %;
    a route seen in one run only is left out."""
    steady = np.linspace(0.0, 100.0 / 0.95, 1001)  # its p95: 100 ms

    def run(scale: float) -> np.ndarray:
        return steady * scale

    spread = p95_interval.between_runs(
        {
            "POST /login": [run(1.0), run(1.05), run(1.5)],
            "GET /lab": [run(1.0), run(1.05), run(1.08)],
            "GET /login": [run(1.0)],
        }
    )
    assert set(spread) == {"POST /login", "GET /lab"}
    assert spread["POST /login"][0] == pytest.approx(1.5) and not spread["POST /login"][1]
    assert spread["GET /lab"][0] == pytest.approx(1.08) and spread["GET /lab"][1]
    line = p95_interval.describe_spread(spread)
    assert "1.29× for the median route (1.08–1.50×)" in line
    assert line.endswith("on 1 of 2 routes")
    assert p95_interval.describe_spread({}).endswith("fewer than two runs a route")
