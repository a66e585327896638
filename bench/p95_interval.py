"""How well one load-test run knows its own p95: a distribution-free interval per route.

A route's p95 in one run is computed from that run's 14–720 requests. If those were
independent draws from one latency distribution, the true 95th percentile ξ would lie
between two of them, the l-th and u-th smallest, with a chance that depends on nothing but
the count. The number of requests below ξ is binomial, B ~ Bin(n, q), so

    P(X_(l) ≤ ξ < X_(u)) = P(l ≤ B ≤ u − 1) = F(u − 1) − F(l − 1),

where F is B's distribution function (Hahn & Meeker, *Statistical Intervals*, 1991, §5.2;
the textbook case is the median of 100 values at 95 %: X_(40) to X_(61)). This interval
does not depend on how the latencies are distributed. A class's requests are not
independent (the burst's are queued behind each other), so between runs the p95 moves by
more than this: the interval is the *least* uncertainty one run's p95 carries, not all of
it. A prediction "within 10 % of a measured run" can only be checked to this resolution.
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Iterator
from pathlib import Path

import numpy as np
from class_cpu import route_of
from scipy.stats import binom

QUANTILE = 0.95
CONFIDENCE = 0.90
COUNTS = ("count", "inside", "within 10 %", "resolved")  # :func:`tally`'s, per route


def order_statistic_ranks(
    count: int, quantile: float = QUANTILE, confidence: float = CONFIDENCE
) -> tuple[int | None, int | None]:
    """The ranks (1-based) l and u of the shortest symmetric distribution-free interval
    [X_(l), X_(u)] for the ``quantile`` of ``count`` independent values:
    l = max{l : F(l − 1) ≤ α/2}, u = min{u : F(u − 1) ≥ 1 − α/2}, α = 1 − confidence,
    F the Bin(count, quantile) distribution function. ``None`` where the values cannot
    bound that side (e.g. 14 values: all 14 fall below the p95 with chance 0.95¹⁴ ≈ 0.49,
    so no value is a 90 % upper bound)."""
    if count < 1:
        return None, None
    tail = (1.0 - confidence) / 2
    ranks = np.arange(1, count + 1)
    below = binom.cdf(ranks - 1, count, quantile)  # F(r − 1) for r = 1 … count
    lower = ranks[below <= tail]
    upper = ranks[below >= 1.0 - tail]
    return (
        int(lower[-1]) if lower.size else None,
        int(upper[0]) if upper.size else None,
    )


def quantile_interval(
    values: np.ndarray, quantile: float = QUANTILE, confidence: float = CONFIDENCE
) -> tuple[float, float]:
    """[X_(l), X_(u)] of ``values`` (:func:`order_statistic_ranks`); −inf / +inf for a
    side the values cannot bound."""
    ordered = np.sort(np.asarray(values, dtype=float))
    low, high = order_statistic_ranks(ordered.size, quantile, confidence)
    return (
        float(ordered[low - 1]) if low else -math.inf,
        float(ordered[high - 1]) if high else math.inf,
    )


def client_lines(path: Path) -> Iterator[tuple[str, str, float, float, str | None]]:
    """Each request the load generator timed: (method, path, sent s, answered s, the
    browser that sent it or None) -- ``GYROLAB_BENCH_CLIENT_TIMES`` lines, ``method path
    sent_s answered_s [who]`` (the browser named since 2026-12-05); a line cut short is
    left out."""
    for line in path.read_text().splitlines():
        fields = line.split()
        if len(fields) in (4, 5):
            who = fields[4] if len(fields) == 5 else None
            yield fields[0], fields[1], float(fields[2]), float(fields[3]), who


def client_requests(path: Path) -> dict[str, np.ndarray]:
    """Per route, each request the load generator timed as a row (sent, latency), s
    (:func:`client_lines`; sent on ``time.perf_counter``'s clock)."""
    rows: dict[str, list[tuple[float, float]]] = defaultdict(list)
    for method, url, sent, answered, _ in client_lines(path):
        rows[route_of(method, url)].append((sent, answered - sent))
    return {route: np.array(values).reshape(-1, 2) for route, values in rows.items()}


def latencies_of(requests: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Per route, the latencies (ms) of :func:`client_requests`' rows."""
    return {route: rows[:, 1] * 1000 for route, rows in requests.items()}


def client_latencies(path: Path) -> dict[str, np.ndarray]:
    """Per route, the latencies (ms) the load generator timed (:func:`client_requests`)."""
    return latencies_of(client_requests(path))


def relative(interval: tuple[int, float, float, float]) -> tuple[float, float]:
    """The interval's ends as per cent of the p95 (−inf / +inf kept)."""
    _, p95, low, high = interval
    return (low / p95 - 1) * 100, (high / p95 - 1) * 100


def describe(interval: tuple[int, float, float, float]) -> str:
    """``−7 / +14 %``, ``−63 / — %`` for an unbounded side."""
    low, high = relative(interval)
    shown = [f"{end:+.0f}" if math.isfinite(end) else "—" for end in (low, high)]
    return f"{shown[0]} / {shown[1]} %"


def intervals_of(latencies: dict[str, np.ndarray]) -> dict[str, tuple[int, float, float, float]]:
    """:func:`run_intervals` of latencies already read (per route, ms)."""
    return {
        route: (len(values), float(np.percentile(values, 95)), *quantile_interval(values))
        for route, values in latencies.items()
    }


def run_intervals(path: Path) -> dict[str, tuple[int, float, float, float]]:
    """Per route of one run: (requests, p95, the p95's 90 % interval low, high), ms, the
    p95 computed as the load test computes it (``np.percentile``)."""
    return intervals_of(client_latencies(path))


Row = tuple[str, tuple[int, float, float, float], float, float, bool]


def score(
    predicted: dict[str, float], intervals: dict[str, tuple[int, float, float, float]]
) -> list[Row]:
    """Per route in both: (route, the run's interval, the predicted p95, its error against
    the run's p95 in per cent, whether it lies inside the interval)."""
    rows = []
    for route in sorted(set(predicted) & set(intervals)):
        interval = intervals[route]
        _, p95, low, high = interval
        model = predicted[route]
        rows.append((route, interval, model, (model - p95) / p95 * 100, low <= model <= high))
    return rows


def resolved(interval: tuple[int, float, float, float]) -> bool:
    """Whether the interval lies within ±10 % of its p95: only then can one run tell a
    prediction 10 % off from one that is right."""
    return all(math.isfinite(end) and abs(end) <= 10 for end in relative(interval))


def tally(rows: list[Row]) -> dict[str, dict[str, int]]:
    """Per route and over all ("all"): "count", "inside", "within 10 %", "resolved"."""
    counts: dict[str, dict[str, int]] = defaultdict(lambda: dict.fromkeys(COUNTS, 0))
    for route, interval, _, error, inside in rows:
        for key in (route, "all"):
            counts[key]["count"] += 1
            counts[key]["inside"] += inside
            counts[key]["within 10 %"] += abs(error) <= 10
            counts[key]["resolved"] += resolved(interval)
    return dict(counts)


def compare(
    predicted: dict[str, float], intervals: dict[str, tuple[int, float, float, float]]
) -> list[Row]:
    """Print each route's predicted p95 beside the run's measured p95 and its interval,
    and the counts (inside the interval, within 10 %, routes whose interval is within
    ±10 %); return :func:`score`'s rows."""
    rows = score(predicted, intervals)
    print(f"  the run's own p95 and its {CONFIDENCE:.0%} interval (order statistics of its"
          " requests: the least a run's p95 is uncertain by)")  # fmt: skip
    print(f"  {'route':42s} {'requests':>8s} {'measured':>8s} {'interval':>14s}"
          f" {'predicted':>9s} {'error':>6s}  inside")  # fmt: skip
    for route, interval, model, error, inside in rows:
        count, p95, _, _ = interval
        print(f"  {route:42s} {count:8d} {p95:8.0f} {describe(interval):>14s} {model:9.0f}"
              f" {error:+5.0f}%  {'yes' if inside else 'no'}")  # fmt: skip
    counts = tally(rows)["all"] if rows else dict.fromkeys(COUNTS, 0)
    print(f"  inside the run's interval: {counts['inside']} of {counts['count']}; within"
          f" 10 %: {counts['within 10 %']}; routes whose interval lies within ±10 %:"
          f" {counts['resolved']}")  # fmt: skip
    return rows


def print_ceiling(measured: list[Row], exact: list[Row]) -> None:
    """Per route, the model against the measured runs beside an exact model against them:
    the model's own seeds it did not predict with, each scored as a run (``exact``). The
    exact model's share within 10 % is the most any prediction of one run can reach."""
    ours, best = tally(measured), tally(exact)
    print(" within 10 % of one run's p95, and inside its interval: the model against the"
          " measured runs | an exact model (the model's unused seeds as runs)")  # fmt: skip
    print(f"  {'route':42s} {'within 10 %':>13s} {'inside':>9s} | {'within 10 %':>13s}"
          f" {'inside':>9s} {'resolved':>9s}")  # fmt: skip

    def share(counts: dict[str, int] | None, key: str) -> str:
        return f"{counts[key]:3d} / {counts['count']:<3d}" if counts else "-"

    for route in sorted(set(ours) | set(best), key=lambda r: (r == "all", r)):
        mine, exact_counts = ours.get(route), best.get(route)
        print(f"  {route:42s} {share(mine, 'within 10 %'):>13s} {share(mine, 'inside'):>9s} |"
              f" {share(exact_counts, 'within 10 %'):>13s} {share(exact_counts, 'inside'):>9s}"
              f" {share(exact_counts, 'resolved'):>9s}")  # fmt: skip


def between_runs(per_run: dict[str, list[np.ndarray]]) -> dict[str, tuple[float, bool]]:
    """Per route with two runs or more, from each run's requests (ms): its p95's largest
    over smallest of the runs, and whether every run's p95 lies within 10 % of the runs'
    median -- how far runs of one class, same code and hour, differ on their own."""
    spread = {}
    for route, runs in per_run.items():
        p95s = np.array([np.percentile(values, 95) for values in runs if len(values)])
        if len(p95s) >= 2 and p95s.min() > 0:
            middle = float(np.median(p95s))
            within = bool(np.all(np.abs(p95s / middle - 1.0) <= 0.10))
            spread[route] = (float(p95s.max() / p95s.min()), within)
    return spread


def describe_spread(spread: dict[str, tuple[float, bool]]) -> str:
    """``between_runs`` in a line."""
    if not spread:
        return "the runs' own spread: fewer than two runs a route"
    ratios = np.array([ratio for ratio, _ in spread.values()])
    within = sum(1 for _, ok in spread.values() if ok)
    return (
        f"the runs' own p95s, largest over smallest: {np.median(ratios):.2f}× for the median"
        f" route ({ratios.min():.2f}–{ratios.max():.2f}×); every run within 10 % of the runs'"
        f" median on {within} of {len(spread)} routes"
    )
