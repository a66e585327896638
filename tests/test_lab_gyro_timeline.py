"""One simulated gyro per lab session: one noise timeline, the table's draws, part B's plane
from part A -- against the stream's own recursion and the noise model's closed forms."""

from __future__ import annotations

import math
import random
from dataclasses import replace
from datetime import UTC, datetime, timedelta

import numpy as np
import pytest

from app.core.exceptions import UserError
from app.core.gyro_stream import GyroStream
from app.core.noise_model import GyroNoise, Window
from app.core.presets import PRESETS
from app.core.solve import solve_heading, solve_latitude
from app.lab.sim import (
    MAX_PAUSE_S,
    SimulatedTake,
    derived_seed,
    gyro_clock_s,
    nominal_angle,
    north_dial_deg,
    set_gyro_clock,
    table_errors,
    turn_on_bias,
)
from app.lab.truth import draw_truth
from app.models import Assignment, LabSession


def session(seed: int = 1, preset: str = "teaching-fog", **fields) -> LabSession:
    values = {
        "owner_id": 1,
        "title": "t",
        "latitude_deg": 39.93,
        "earth_rate_deg_h": 15.041,
        "simulator_preset": preset,
        "sim_seed": seed,
        "sim_azimuth_deg": 33.0,
    }
    return LabSession(**(values | fields))


def level(**fields) -> dict:
    """A table without tilt or misalignment, so only the gyro's noise remains."""
    return {"sim_pitch_deg": 0.0, "sim_roll_deg": 0.0, "sim_misalign_h_deg": 0.0,
            "sim_misalign_v_deg": 0.0} | fields  # fmt: skip


def test_a_recording_continues_the_sessions_one_noise_timeline():
    lab = session(7, "tactical-fog")  # 10 Hz
    take = SimulatedTake(lab, "heading", 1, settle_s=2.0, start_s=98.0)
    values, times = take.next(50)
    stream = GyroStream(PRESETS["tactical-fog"], derived_seed(lab, "gyro", 0))
    stream.turn_on_bias_deg_h = turn_on_bias(lab)
    stream.read(np.zeros(1000))  # the gyro ran (at rest, turned, waiting) for 100 s
    expected = stream.read(np.full(50, take.true_rate), take.up)
    assert np.array_equal(values, expected)
    assert times[0] == 100.0 and times[-1] == pytest.approx(104.9) and take.end_s == 105.0
    again = SimulatedTake(lab, "heading", 1, settle_s=2.0, start_s=98.0).next(50)[0]
    assert np.array_equal(values, again)  # deterministic from the stored seed and clock


def test_a_live_recording_read_frame_by_frame_is_the_same_timeline():
    """The stream asks for a few samples per frame and the take makes its noise ahead in
    blocks: the same samples and times as one read, across several blocks."""
    lab = session(11, "tactical-fog")
    whole_values, whole_times = SimulatedTake(lab, "latitude", 2, start_s=40.0).next(3000)
    take = SimulatedTake(lab, "latitude", 2, start_s=40.0)
    pieces = [take.next(count) for count in [1, 40, 39, 1500, 7, 1413]]
    assert np.array_equal(np.concatenate([v for v, _ in pieces]), whole_values)
    assert np.array_equal(np.concatenate([t for _, t in pieces]), whole_times)
    assert take.end_s == whole_times[-1] + 0.1
    # a take built with its dwell (the stream's, in the thread pool) makes that much at
    # once, and then in blocks past it: the same timeline
    made = SimulatedTake(lab, "latitude", 2, start_s=40.0, dwell_s=120.0)
    assert made.samples_in(120.0) == 1200 and made.produced == 0
    pieces = [made.next(count) for count in [40, 1160, 1, 1799]]
    assert np.array_equal(np.concatenate([v for v, _ in pieces]), whole_values)
    assert made.end_s == take.end_s


def test_a_long_history_is_replayed_once_and_every_take_is_the_same(monkeypatch):
    """A gyro left on for hours: the state after its history is kept per stream, and each
    later recording replays only the time since -- the same samples as a replay from
    switch-on (written out here with the stream's own recursion), whatever is kept, for
    each session alone, and for a take starting before a kept state."""
    from app.lab import gyro_history

    gyro_history.KEPT.clear()
    replayed: list[int] = []
    replay = gyro_history.replay
    monkeypatch.setattr(
        gyro_history, "replay", lambda stream, n: (replayed.append(n), replay(stream, n))
    )

    def from_switch_on(lab, take, start_s: float, count: int) -> np.ndarray:
        stream = GyroStream(PRESETS["tactical-fog"], derived_seed(lab, "gyro", 0))
        stream.turn_on_bias_deg_h = turn_on_bias(lab)
        stream.read(np.zeros(int(round(start_s * 10))))
        return stream.read(np.full(count, take.true_rate), take.up)

    first, second = session(21, "tactical-fog"), session(22, "tactical-fog")
    starts = [(first, 3600.0), (second, 3600.0), (first, 3700.0), (first, 5400.0)]
    for lab, start in [*starts, (first, 2000.0)]:
        take = SimulatedTake(lab, "heading", 1, start_s=start)
        assert np.array_equal(take.next(40)[0], from_switch_on(lab, take, start, 40))
    # from switch-on, for each session, then only the time since; an earlier start anew
    assert replayed == [36_000, 36_000, 1_000, 17_000, 20_000]
    assert SimulatedTake(first, "heading", 1, start_s=30.0).stream.samples_read == 300
    assert replayed[-1] == 300  # too short a history to be worth keeping
    gyro_history.KEPT.clear()


def test_slow_bias_carries_across_positions_as_the_noise_model_says():
    """Means of two 300 s recordings of the teaching gyro 20 s apart, over 400 sessions:
    their covariance matches the continuous-timeline covariance of app.core.noise_model
    (closed form), far from the zero that separate recordings would give.  (The warm-up is
    the same in every session, so it drops out of the covariance.)"""
    windows = [Window(600.0, 300.0), Window(920.0, 300.0)]
    errors = []
    for seed in range(400):
        lab = session(seed, **level())
        means = []
        for position, window in zip((1, 2), windows, strict=True):
            take = SimulatedTake(lab, "heading", position, start_s=window.start_s)
            values, _ = take.next(int(window.length_s * take.rate_hz))
            means.append(values.mean() - take.true_rate * (1 + 500e-6) - turn_on_bias(lab))
        errors.append(means)
    measured = np.cov(np.asarray(errors).T)
    model = GyroNoise.from_preset(PRESETS["teaching-fog"]).mean_covariance(windows, warm_up=False)
    correlation = model[0, 1] / math.sqrt(model[0, 0] * model[1, 1])
    assert correlation > 0.2
    found = measured[0, 1] / math.sqrt(measured[0, 0] * measured[1, 1])
    assert found == pytest.approx(correlation, abs=4 * (1 - correlation**2) / math.sqrt(400))
    assert np.sqrt(np.diag(measured)) == pytest.approx(np.sqrt(np.diag(model)), rel=0.12)


def test_the_clock_runs_between_recordings_and_a_long_pause_is_capped():
    lab = session(3)
    start = datetime(2026, 11, 22, 9, 0, tzinfo=UTC)
    set_gyro_clock(lab, 250.0, start)
    assert gyro_clock_s(lab, start + timedelta(seconds=95)) == pytest.approx(345.0)
    assert gyro_clock_s(lab, start + timedelta(days=3)) == pytest.approx(250.0 + MAX_PAUSE_S)
    assert gyro_clock_s(lab, start - timedelta(seconds=5)) == pytest.approx(250.0)
    lab.sim_clock_at = start.replace(tzinfo=None)  # as SQLite may hand it back
    assert gyro_clock_s(lab, start + timedelta(seconds=1)) == pytest.approx(251.0)


def _latitude_of(lab: LabSession, seconds: float = 120.0) -> float:
    clock, positions, angles = 60.0, [], []
    for position in range(1, 5):
        lab.sim_table_latitude = position
        lab.sim_turns += 1
        take = SimulatedTake(lab, "latitude", position, start_s=clock)
        values, _ = take.next(int(seconds * take.rate_hz))
        clock = take.end_s + 20.0
        positions.append(values)
        angles.append(take.dial_angle_deg)
    return solve_latitude(positions, angles).latitude_deg


def test_part_b_runs_in_the_plane_the_student_set_after_part_a():
    """Axis in the vertical plane at azimuth ψ: ω = Ω cos φ cos ψ cos e + Ω sin φ sin e, so the
    fitted latitude is atan2(sin φ, cos φ cos ψ) (closed form), exact north only at ψ = 0."""
    phi = math.radians(39.93)
    for offset in (0.0, 25.0, -40.0):
        lab = session(11, "navigation-fog", **level())
        lab.sim_plane_dial_deg = north_dial_deg(lab, lab.sim_azimuth_deg, 0.0) + offset
        expected = math.degrees(
            math.atan2(math.sin(phi), math.cos(phi) * math.cos(math.radians(offset)))
        )
        assert _latitude_of(lab) == pytest.approx(expected, abs=0.05)
    # never set: the plane of the table's last part-A stop
    lab = session(11, "navigation-fog", **level(), sim_azimuth_deg=300.0)
    lab.sim_table_heading = 4  # ccw: position 4 points 270° anticlockwise = 90° clockwise
    psi = lab.sim_azimuth_deg + 90.0
    expected = math.degrees(math.atan2(math.sin(phi), math.cos(phi) * math.cos(math.radians(psi))))
    assert _latitude_of(lab) == pytest.approx(expected, abs=0.05)


def test_north_from_part_a_carries_into_latitude():
    """The whole bench: part A, turn to the north it found, part B.  The latitude is what the
    miss in north predicts; turning to south instead (the handout's sign check skipped)
    puts Earth's axis behind the gyro and the fit lands beyond 90°."""
    lab = session(5, "navigation-fog", **level(sim_misalign_h_deg=3.0))
    clock, positions, angles = 3600.0, [], []  # a warm gyro
    for position in range(1, 5):
        lab.sim_table_heading = position
        lab.sim_turns += 1
        take = SimulatedTake(lab, "heading", position, start_s=clock)
        values, _ = take.next(3000)
        clock = take.end_s + 20.0
        positions.append(values)
        angles.append(take.dial_angle_deg)
    heading = solve_heading(positions, angles)
    # the axis, 3° off the dial zero, is what the gyro finds: it points north in part B too
    assert heading.azimuth_deg == pytest.approx(lab.sim_azimuth_deg + 3.0, abs=0.05)
    lab.sim_plane_dial_deg = north_dial_deg(lab, heading.azimuth_deg, angles[0])
    miss = math.radians(heading.azimuth_deg - 3.0 - lab.sim_azimuth_deg)
    phi = math.radians(39.93)
    expected = math.degrees(math.atan2(math.sin(phi), math.cos(phi) * math.cos(miss)))
    assert _latitude_of(lab) == pytest.approx(expected, abs=0.05)
    assert expected == pytest.approx(39.93, abs=0.01)
    lab.sim_plane_dial_deg += 180.0
    with pytest.raises(UserError) as error:
        _latitude_of(lab)
    assert error.value.key == "readings.latitude_out_of_range"


def test_turntable_tilt_and_misalignment_come_from_the_assignment_or_the_preset():
    assignment = Assignment(course_id=1, title="a", latitude_deg=40.0, table_tilt_max_deg=2.0,
                            misalignment_max_deg=0.5)  # fmt: skip
    drawn = []
    for seed in range(50):
        lab = session(seed)
        draw_truth(assignment, lab, random.Random(seed))
        table = table_errors(lab)
        assert abs(table["pitch_deg"]) <= 2.0 and abs(table["roll_deg"]) <= 2.0
        assert abs(table["misalign_h_deg"]) <= 0.5 and abs(table["misalign_v_deg"]) <= 0.5
        drawn.append(table["pitch_deg"])
    assert np.std(drawn) > 0.5  # really drawn, not all zero
    own = [table_errors(session(seed))["roll_deg"] for seed in range(200)]
    assert np.std(own) == pytest.approx(PRESETS["teaching-fog"].table_tilt_sigma_deg, rel=0.2)


def test_a_tilted_table_biases_the_heading_as_tan_phi_times_the_east_west_tilt():
    """lab-reference §4: an east–west tilt t_E of the rotation axis gives ≈ tan φ · t_E."""
    lab = session(2, "navigation-fog", **level(sim_roll_deg=1.0), sim_azimuth_deg=0.0)
    positions, angles, clock = [], [], 60.0
    for position in range(1, 5):
        lab.sim_turns += 1
        take = SimulatedTake(lab, "heading", position, start_s=clock)
        values, _ = take.next(1200)
        clock = take.end_s + 20.0
        positions.append(values)
        angles.append(take.dial_angle_deg)
    error = solve_heading(positions, angles).azimuth_deg
    error = (error + 180.0) % 360.0 - 180.0
    assert abs(error) == pytest.approx(math.tan(math.radians(39.93)) * 1.0, abs=0.08)


def _heading_error(lab: LabSession, positions: int, seconds: float = 100.0) -> tuple:
    clock, values, times, angles = 60.0, [], [], []  # recorded a minute after switch-on
    for position in range(1, positions + 1):
        lab.sim_turns += 1
        take = SimulatedTake(lab, "heading", position, start_s=clock)
        samples, stamps = take.next(int(seconds * take.rate_hz))
        clock = take.end_s + 20.0
        values.append(samples)
        times.append(stamps)
        angles.append(take.dial_angle_deg)
    result = solve_heading(values, angles, times_s=times)
    axis = lab.sim_azimuth_deg + table_errors(lab)["misalign_h_deg"]
    return (result.azimuth_deg - axis + 180.0) % 360.0 - 180.0, result


def test_the_symmetric_order_cancels_a_linear_drift(monkeypatch):
    """Positions 5–8 revisit 4–1 at the same dial angles.  With a linear bias drift ḃ the
    order 1-2-3-4 errs by ≈ ḃ·T·(sin A − cos A)/H (lab-reference §3, T the time between
    stops); 1-2-3-4-4-3-2-1 with the gyro's times fits ḃ and lands within its σ."""
    drifting = replace(PRESETS["navigation-fog"].without("warmup"), drift_deg_h_per_h=2.0)
    monkeypatch.setitem(PRESETS, "drifting", drifting)
    lab = session(3, "drifting", sim_azimuth_deg=135.0, **level())
    assert [nominal_angle(lab, "heading", k) for k in range(1, 5)] == [0, -90, -180, -270]
    plain, _ = _heading_error(lab, 4)
    spacing_h = 120.0 / 3600.0  # 100 s of readings + 20 s turning
    amplitude = 15.041 * math.cos(math.radians(39.93))
    a = math.radians(135.0)
    expected = math.degrees(2.0 * spacing_h * (math.sin(a) - math.cos(a)) / amplitude)
    assert plain == pytest.approx(expected, rel=0.15)
    lab = session(3, "drifting", sim_azimuth_deg=135.0, symmetric_order=True, **level())
    assert [nominal_angle(lab, "heading", k) for k in range(5, 9)] == [-270, -180, -90, 0]
    error, result = _heading_error(lab, 8)
    assert result.fit.drift == pytest.approx(2.0, abs=4 * result.fit.drift_sigma)
    assert abs(error) < 4 * result.azimuth_sigma_deg
    assert abs(plain) > 5 * abs(error)  # the rest is the flicker bias's own wander


def test_the_symmetric_order_halves_a_cold_gyros_warm_up_error():
    """The warm-up is not linear (b₀e^(−t/τ)), so a cold start still hurts in any order:
    the symmetric order removes the linear part (median over 12 cold sessions: ≥ 2× smaller);
    waiting removes the rest."""
    plain, symmetric = [], []
    for seed in range(12):
        lab = session(seed, sim_azimuth_deg=135.0, **level())
        plain.append(abs(_heading_error(lab, 4)[0]))
        lab = session(seed, sim_azimuth_deg=135.0, symmetric_order=True, **level())
        symmetric.append(abs(_heading_error(lab, 8)[0]))
    assert np.median(plain) > 2 * np.median(symmetric)
