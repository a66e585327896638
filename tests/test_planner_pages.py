"""The accuracy planner in the app: the student's page and API before recording, and the
teacher's comparison of the class's scatter with it (issue 35, item 3)."""

from __future__ import annotations

import html
import math

import pytest
from sqlmodel import select

from app.core.accuracy_plan import plan_point
from app.core.noise_model import GyroNoise
from app.core.presets import PRESETS
from app.db import write_session
from app.models import LabSession
from tests.factories import API, browser, do_lab, set_assignment, start, submit, token_for


def test_the_student_sees_the_plan_before_recording_and_the_api_gives_the_same(world):
    student = browser(world, "s1")
    session_id = start(student, world)
    page = student.get(f"/lab/sessions/{session_id}").text
    preset = PRESETS["teaching-fog"]
    expected = plan_point(
        GyroNoise.from_preset(preset), preset.sample_rate_hz, 60.0, "1234", 39.93, 15.04
    )
    heading = f"±{expected.heading_sigma_deg:.2f}°"
    assert 'id="accuracy-plan"' in page
    assert f"With 60 s per position expect {heading} in the heading" in page
    assert "Teaching FOG" in page and "indexing and reading errors come on top" in page

    auth = token_for(student, "s1")
    plan = student.get(f"{API}/sessions/{session_id}/plan", headers=auth).json()
    assert plan["source"] == "preset" and plan["quoted_dwell_s"] == 60.0
    point = next(p for p in plan["points"] if p["order"] == "1234" and p["dwell_s"] == 60.0)
    assert point["heading_sigma_deg"] == pytest.approx(expected.heading_sigma_deg)
    assert {p["order"] for p in plan["points"]} == {"1234", "12344321"}
    assert plan["near_best"]["1234"]["dwell_s"] <= plan["best"]["1234"]["dwell_s"]

    chinese = student.get(f"/lab/sessions/{session_id}", headers={"Accept-Language": "zh-CN"})
    assert f"预期航向 {heading}" in chinese.text


@pytest.mark.parametrize(
    ("true_heading", "verdict", "words"),
    [
        (11.5, "larger", "More scatter than the gyro's noise explains"),
        (10.76, "smaller", "Less scatter than the gyro's noise allows"),
    ],
)
def test_the_class_scatter_is_compared_with_the_plan(world, true_heading, verdict, words):
    """Three groups hand in the handout's data (10 readings a position: 100 s at the
    teaching FOG's 0.1 Hz), 10.75°: 0.75° from a truth of 11.5° is about five predicted σ
    (far more than noise), 0.01° from 10.76° far less than the noise allows."""
    set_assignment(world, true_heading_deg=true_heading)
    for name in ("s1", "s2", "s3"):
        student = browser(world, name)
        session_id = start(student, world)
        do_lab(student, session_id)
        submit(student, session_id)
    teacher = browser(world, "teacher1")
    auth = token_for(teacher, "teacher1")
    accuracy = teacher.get(f"{API}/assignments/{world['assignment']}/accuracy", headers=auth)
    assert accuracy.status_code == 200
    heading = accuracy.json()["heading"]
    preset = PRESETS["teaching-fog"]
    sigma = plan_point(
        GyroNoise.from_preset(preset), preset.sample_rate_hz, 100.0, "1234", 39.93, 15.04
    ).heading_sigma_deg
    assert heading["groups"] == 3 and heading["median_dwell_s"] == 100.0
    assert heading["predicted_sigma"] == pytest.approx(sigma)
    error = 10.75 - true_heading  # the handout's azimuth, every group the same
    assert heading["measured_rms"] == pytest.approx(abs(error), abs=0.01)
    assert heading["ratio"] == pytest.approx(heading["measured_rms"] / sigma, rel=1e-9)
    assert heading["verdict"] == verdict
    assert heading["low"] == pytest.approx(math.sqrt(0.2158 / 3), abs=1e-3)  # χ²_3(2.5 %)

    page = html.unescape(
        teacher.get(f"/courses/{world['course']}/assignments/{world['assignment']}").text
    )
    assert f'data-quantity="heading" data-verdict="{verdict}"' in page
    assert words in page
    with write_session() as db:
        assert len(db.exec(select(LabSession)).all()) == 3


def test_a_student_cannot_read_the_class_accuracy(world):
    student = browser(world, "s1")
    auth = token_for(student, "s1")
    response = student.get(f"{API}/assignments/{world['assignment']}/accuracy", headers=auth)
    assert response.status_code in (403, 404)


def test_groups_whose_device_is_faster_than_the_characterisation_are_planned_for_their_span(
    world,
):
    """The station's gyro characterised from a 10 Hz record; three groups send it at 1 kHz
    with the times, 5000 readings (5 s) a position.  The class's predicted σ is the plan's
    for 5 s, as each group's own σ is (their readings' span), not for the 500 s their count
    makes at 10 Hz -- which predicted ten times too little and called honest scatter
    "larger" than the gyro's noise."""
    import json

    import numpy as np

    from app.models import Assignment

    arw, count, rate = 0.01, 5000, 1000.0
    summary = {"arw_deg_rt_h": arw, "bias_instability_deg_h": 0.0, "rrw_deg_h_rt_h": 0.0,
               "quantization_deg": 0.0, "rate_hz": 10.0, "terms": {}}  # fmt: skip
    with write_session() as db:
        db.get(Assignment, world["assignment"]).gyro_characterisation = json.dumps(summary)
    set_assignment(world, true_heading_deg=30.0)
    h = 15.04 * math.cos(math.radians(39.93))
    rng = np.random.default_rng(3)
    for name in ("s1", "s2", "s3"):
        student = browser(world, name)
        auth = token_for(student, name)
        body = {"assignment_id": world["assignment"]}
        session_id = student.post(f"{API}/sessions", json=body, headers=auth).json()["id"]
        for k, angle in enumerate((0.0, -90.0, -180.0, -270.0), 1):
            values = h * np.cos(np.radians(30.0 + angle)) + rng.normal(0.0, 19.0, count)
            upload = {"samples": values.tolist(),
                      "times_s": (100.0 * k + np.arange(count) / rate).tolist()}  # fmt: skip
            url = f"{API}/sessions/{session_id}/heading/positions/{k}"
            assert student.put(url, json=upload, headers=auth).status_code == 200
        assert student.post(f"{API}/sessions/{session_id}/submit", headers=auth).status_code == 200
    teacher = browser(world, "teacher1")
    auth = token_for(teacher, "teacher1")
    heading = teacher.get(f"{API}/assignments/{world['assignment']}/accuracy", headers=auth)
    heading = heading.json()["heading"]
    noise = GyroNoise(arw_deg_rt_h=arw, bias_instability_deg_h=0.0, rrw_deg_h_rt_h=0.0)
    expected = plan_point(noise, 10.0, 5.0, "1234", 39.93, 15.04).heading_sigma_deg
    assert heading["groups"] == 3 and heading["median_dwell_s"] == pytest.approx(5.0)
    assert heading["predicted_sigma"] == pytest.approx(expected, rel=1e-9)
