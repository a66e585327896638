"""A session's results: the current take of each position, solved per part with the
σ the data supports (the simulator's or the bench gyro's noise model), worked steps and
data-quality flags."""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, field, replace
from itertools import groupby, pairwise
from types import SimpleNamespace

import numpy as np
from sqlalchemy import bindparam
from sqlmodel import Session, select

from app.core.exceptions import UserError
from app.core.explain import explain_heading, explain_latitude
from app.core.noise_model import GyroNoise, Window
from app.core.solve import solve_heading, solve_latitude
from app.courses.characterisation import StationNoise, station_noise
from app.lab.recent_samples import RECENT
from app.lab.result_flags import quality_flags, unit_slip_flag, warm_up_flag
from app.lab.samples import unpack_all
from app.lab.sim import preset_for
from app.lab.store import PARTS, current_takes
from app.models import (
    Assignment,
    InputMethod,
    LabSession,
    SampleChunk,
    Take,
)


@dataclass
class PositionData:
    """A position's readings as the result uses them: after the take's trimmed start.

    ``n``, ``mean`` and ``std`` (sample, ddof = 1; None below 2 readings) summarise the
    used readings; a cached result keeps them and drops ``values``/``times`` (``slim``)."""

    take: Take
    values: np.ndarray | None
    times: np.ndarray | None
    n: int = 0
    mean: float = math.nan
    std: float | None = None
    temperatures: np.ndarray | None = None  # °C, when the instrument reported them

    @classmethod
    def of(
        cls,
        take: Take,
        values: np.ndarray,
        times: np.ndarray | None,
        temperatures: np.ndarray | None = None,
    ) -> PositionData:
        """All of a take's samples → the ones used (the first ``take.trim_start`` are the
        transient after turning the table: kept in the database, left out here)."""
        start = min(max(take.trim_start or 0, 0), values.size)
        used = values[start:]
        return cls(
            take,
            used,
            None if times is None else times[start:],
            n=int(used.size),
            mean=float(used.mean()) if used.size else math.nan,
            std=float(used.std(ddof=1)) if used.size > 1 else None,
            temperatures=None if temperatures is None else temperatures[start:],
        )

    @property
    def trimmed(self) -> int:
        return self.take.trim_start or 0

    @property
    def sem(self) -> float | None:
        """s/√n of the used readings (None below 2 readings)."""
        return None if self.std is None else self.std / math.sqrt(self.n)

    def slim(self) -> PositionData:
        """The summary without the samples, and the take as a detached snapshot (safe to
        share between requests and threads)."""
        take = self.take
        if not isinstance(take, SimpleNamespace):  # a snapshot already (iter_current_data)
            take = SimpleNamespace(**take.model_dump())
        return PositionData(take, None, None, self.n, self.mean, self.std)


@dataclass
class PartResult:
    part: str
    positions: dict[int, PositionData]
    result: object | None = None  # HeadingResult | LatitudeResult
    error: UserError | None = None
    steps: list = field(default_factory=list)
    flags: list[dict] = field(default_factory=list)

    def to_json(self) -> dict | None:
        return None if self.result is None else self.result.to_json()

    def slim(self) -> PartResult:
        """The same result without the samples (see :meth:`PositionData.slim`)."""
        positions = {k: item.slim() for k, item in self.positions.items()}
        return PartResult(self.part, positions, self.result, self.error, self.steps, self.flags)


SessionData = dict[str, dict[int, PositionData]]  # part → position → data


def _assemble(take: Take, rows: list) -> PositionData:  # rows: a take's chunks, in order
    values = unpack_all([r.values for r in rows])
    times = temperatures = None
    if rows and all(r.times is not None for r in rows):
        times = unpack_all([r.times for r in rows])
    if rows and all(r.temperatures is not None for r in rows):
        temperatures = unpack_all([r.temperatures for r in rows])
    return PositionData.of(take, values, times, temperatures)


# the samples of several takes, in one statement built once (an expanding IN list), through
# Core: rows, not objects
CHUNK_COLUMNS_OF_TAKES = (
    select(SampleChunk.take_id, SampleChunk.values, SampleChunk.times, SampleChunk.temperatures)
    .where(SampleChunk.take_id.in_(bindparam("take_ids", expanding=True)))
    .order_by(SampleChunk.take_id, SampleChunk.seq)
)
TAKES_PER_READ = 64  # takes whose samples one statement reads (and memory holds) at most


def iter_takes_data(db: Session, takes: list) -> Iterator[PositionData]:
    """Each given take's :class:`PositionData` with its samples, in no set order: those
    this process has just written from memory (``recent_samples``), the others read
    :data:`TAKES_PER_READ` takes a statement, so that only so many are in memory at once
    (``takes``: Take rows or snapshots with their columns)."""
    unread = []
    for take in takes:
        held = RECENT.get(take)
        if held is None:
            unread.append(take)
        else:
            yield PositionData.of(take, *held)
    connection = db.connection()
    for start in range(0, len(unread), TAKES_PER_READ):
        batch = {take.id: take for take in unread[start : start + TAKES_PER_READ]}
        rows = connection.execute(CHUNK_COLUMNS_OF_TAKES, {"take_ids": list(batch)}).all()
        for take_id, group in groupby(rows, key=lambda row: row.take_id):
            yield _assemble(batch[take_id], list(group))


def current_data(db: Session, session: LabSession) -> SessionData:
    """All current positions of one session with their samples: the takes, then the
    samples of those this process has not just written (``recent_samples``)."""
    return takes_data(db, current_takes(db, session.id))


def takes_data(db: Session, takes: list[Take]) -> SessionData:
    """Given takes (one per part and position) with their samples: those this process has
    just written from memory (``recent_samples``), the others read (:func:`iter_takes_data`)."""
    data: SessionData = {}
    for item in iter_takes_data(db, takes):
        data.setdefault(item.take.part, {})[item.take.position] = item
    return {part: dict(sorted(data[part].items())) for part in sorted(data)}


def simulated_noise(session: LabSession, ordered: list[PositionData]) -> dict:
    """When every position was recorded from the simulated gyro its noise model is known:
    the position means' covariance and the table's indexing σ, for the solver.  Recordings
    on the session's one gyro timeline (sample times in gyro seconds, not overlapping) are
    correlated through the slow bias and the random walk; recordings made before the
    timeline existed are separate runs.  Otherwise nothing (the σ assumes white noise)."""
    if not ordered or any(p.take.source != InputMethod.simulator for p in ordered):
        return {}
    preset = preset_for(session)
    noise = GyroNoise.from_preset(preset)
    length = [p.values.size / preset.sample_rate_hz for p in ordered]
    windows = [
        Window(float(p.times[0]) if p.times is not None and p.times.size else 0.0, span)
        for p, span in zip(ordered, length, strict=True)
    ]
    spans = sorted((w.start_s, w.end_s) for w in windows)
    on_one_clock = all(end <= start + 1e-6 for (_, end), (start, _) in pairwise(spans))
    if not on_one_clock:
        windows = [Window(0.0, span) for span in length]
    return {
        "position_cov": noise.mean_covariance(windows, continuous=on_one_clock),
        "indexing_sigma_deg": noise.indexing_sigma_deg,
        "warm_up_cov": noise.warm_up_cov(windows) if on_one_clock else None,
    }


def characterised_noise(station: StationNoise | None, ordered: list[PositionData]) -> dict:
    """Readings from a real gyro the teacher characterised (typed, CSV, API, bridge): each
    position mean's variance from its noise model over the position's recording, taken as
    separate recordings (their timing on the bench is not known), each as long as
    :func:`recorded_seconds` says."""
    if (
        station is None
        or not ordered
        or any(p.take.source == InputMethod.simulator for p in ordered)
    ):
        return {}
    windows = [Window(0.0, recorded_seconds(p, station.rate_hz)) for p in ordered]
    return {"position_cov": station.noise.mean_covariance(windows, continuous=False)}


def recorded_seconds(position: PositionData, rate_hz: float) -> float:
    """How long a position's used readings average over: their count at ``rate_hz`` (the
    characterisation's), or, where they have times spanning less (first to last time plus
    one median step), that span.

    A device sampling faster than the characterisation's record (1 kHz against 10 Hz)
    averages over its own span: its count alone made 5 s of readings 500 s long and their
    σ 10× too small.  A span longer than the count allows is not taken: readings logged
    at 10 s steps from a 10 Hz gyro are single samples (each as noisy as the count says),
    and an integrating output at a slower rate only makes the count's σ cautious."""
    counted = position.values.size / rate_hz
    times = position.times
    if times is not None and times.size >= 2:
        span = float(times[-1] - times[0]) + float(np.median(np.diff(times)))
        if math.isfinite(span) and 0.0 < span < counted:
            return span
    return counted


def station_noise_for(db: Session, session: LabSession) -> StationNoise | None:
    if session.assignment_id is None:
        return None
    return station_noise(db.get(Assignment, session.assignment_id))


def solve_part(
    session: LabSession,
    part: str,
    data: dict[int, PositionData],
    station: StationNoise | None = None,
) -> PartResult:
    outcome = PartResult(part, data)
    if len(data) < 3:
        outcome.error = UserError(
            "lab.need_positions",
            recorded=len(data),
        )
        return outcome
    ordered = [data[k] for k in sorted(data)]
    values = [p.values for p in ordered]
    angles = [p.take.angle_deg for p in ordered]
    known = simulated_noise(session, ordered) or characterised_noise(station, ordered)
    if all(p.times is not None for p in ordered):
        # timed on one clock: the symmetric order's fit adds b + ḃ·(t − t̄); four positions
        # are checked for a drifting bias (a gyro still warming up)
        known["times_s"] = [p.times for p in ordered]
    if any(p.temperatures is not None for p in ordered):
        known["temperatures_c"] = [p.temperatures for p in ordered]
    try:
        if part == "heading":
            expected = session.earth_rate_deg_h * math.cos(math.radians(session.latitude_deg))
            outcome.result = solve_heading(
                values, angles, expected_amplitude_deg_h=expected, **known
            )
            outcome.steps = explain_heading(outcome.result)
        else:
            outcome.result = solve_latitude(
                values,
                angles,
                true_latitude_deg=session.latitude_deg,
                true_earth_rate_deg_h=session.earth_rate_deg_h,
                **known,
            )
            outcome.steps = explain_latitude(outcome.result)
    except UserError as error:
        outcome.error = error
    outcome.flags = quality_flags(session, data)
    if (slip := unit_slip_flag(session, part, ordered, outcome.result)) is not None:
        outcome.flags.insert(0, slip)  # the first thing to put right
    check = outcome.result.drift_check if outcome.result is not None else None
    if check is not None and check.flagged:
        until = None
        if all(p.take.source == InputMethod.simulator and p.times is not None for p in ordered):
            until = max(float(p.times[-1]) for p in ordered if p.times.size)
        outcome.flags.append(warm_up_flag(session, check, until))
    elif outcome.result is not None and outcome.result.fit.closure_consistent is False:
        fit = outcome.result.fit
        outcome.flags.append(
            {
                "key": "flag.closure",
                "params": {"d": f"{fit.closure_residual:.3f}", "sigma": f"{fit.closure_sigma:.3f}"},
            }
        )
    return outcome


def session_results(db: Session, session: LabSession) -> dict[str, PartResult]:
    data = current_data(db, session)
    station = station_noise_for(db, session)
    return {part: solve_part(session, part, data.get(part, {}), station) for part in PARTS}


def with_samples(db: Session, session: LabSession, parts: dict[str, PartResult]) -> dict:
    """Cached (slim) results with their positions' samples read again -- what a solve of
    the same data gives, without solving it again (the page's figures draw the samples
    beside the fit; solving was half of a session's first view)."""
    data = current_data(db, session)
    return {part: replace(outcome, positions=data.get(part, {})) for part, outcome in parts.items()}


def results_json(results: dict[str, PartResult]) -> dict:
    """Each part's result as JSON with its data-quality flags (``flags``: key and params),
    None for a part without one -- what an attempt freezes and an export holds."""
    out = {}
    for part, outcome in results.items():
        result = outcome.to_json()
        out[part] = None if result is None else {**result, "flags": list(outcome.flags)}
    return out
