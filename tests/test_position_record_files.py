"""One position's record as a real gyro's logger writes it -- one reading per line, or
its clock and the reading, a header with units -- uploaded on the lab page's CSV method
for the position the student chooses: previewed with the first position not yet
recorded suggested, saved with its times, and refused with a reason where it is not one."""

from __future__ import annotations

import datetime as dt

import numpy as np
import pytest
from sqlmodel import select

from app.db import read_session
from app.lab.samples import unpack
from app.models import SampleChunk, Take
from tests.factories import HEADING, login, new_session, post_json

# the file's reading is the new part; the saving is the CSV method's, tested on both databases
pytestmark = pytest.mark.one_backend


@pytest.fixture
def lab(client, student):
    assert login(client, "student1").status_code == 303
    session_id = new_session(client)
    page = f"/lab/sessions/{session_id}"

    def send(path: str, text: str, **extra):
        body = {"part": "heading", "unit": "deg/h", "text": text, **extra}
        return post_json(client, page + path, body, page)

    return send


def logger_file(values, start=dt.datetime(2026, 11, 28, 14, 0, 0), step_s=0.5) -> str:
    stamps = (start + dt.timedelta(seconds=k * step_s) for k in range(len(values)))
    return "Time,Rate (deg/h)\n" + "".join(
        f"{t:%Y-%m-%d %H:%M:%S.%f},{v}\n" for t, v in zip(stamps, values, strict=True)
    )


def test_a_loggers_file_for_one_position_previewed_then_saved_where_chosen(lab):
    values = HEADING[2]  # the handout's position 2
    preview = lab("/csv/preview", logger_file(values))
    assert preview.status_code == 200, preview.text
    body = preview.json()
    assert body["layout"] == "record" and body["position_count"] == 4
    [row] = body["positions"]
    assert row["position"] == 1 and row["n"] == len(values)  # the first not yet recorded
    assert row["mean_deg_h"] == pytest.approx(np.mean(values))
    assert "one position's record" in body["notes"][0]
    chosen = lab("/csv/preview", logger_file(values), position=2).json()["positions"][0]
    assert chosen["position"] == 2 and abs(chosen["angle_deg"] - row["angle_deg"]) == 90.0
    refused = lab("/csv", logger_file(values))
    assert refused.status_code == 400 and "choose the position" in refused.json()["detail"]
    saved = lab("/csv", logger_file(values), position=2)
    assert saved.status_code == 200 and saved.json()["saved"] == [2]
    with read_session() as db:
        [take] = db.exec(select(Take)).all()
        chunk = db.exec(select(SampleChunk)).first()
    assert (take.part, take.position, take.n_samples) == ("heading", 2, len(values))
    assert unpack(chunk.times)[:3].tolist() == [0.0, 0.5, 1.0]  # the logger's clock
    # the next file suggests the first position still empty
    assert lab("/csv/preview", logger_file(values)).json()["positions"][0]["position"] == 1


def test_one_reading_per_line_is_one_positions_record(lab):
    text = "".join(f"{v}\n" for v in HEADING[3])
    saved = lab("/csv", text, position=3)
    assert saved.status_code == 200 and saved.json()["saved"] == [3]


@pytest.mark.parametrize(
    ("text", "unit", "message"),
    [
        ("Time (s),Rate (deg/s)\n0,0.003\n0.5,0.004\n", "deg/h", "in °/s, but °/h is chosen"),
        ("time_s,dtheta [rad]\n0,1e-7\n0.1,2e-7\n", "deg/h", "gives angles in rad, not rates"),
        ("time_s,value\n0,10.7\n0.5,abc\n", "deg/h", "Line 3 of the record is not a reading"),
        ("hello,world\n1,2\n", "deg/h", "reads 'hello | world'"),  # names of no record
        ("10.7,10.1\n10.6,10.2\n10.8,10.0\n", "deg/h", "reads '10.7 | 10.1'"),  # not times
    ],
)
def test_what_is_no_record_or_a_bad_one_says_why(lab, text, unit, message):
    for path in ("/csv/preview", "/csv"):
        response = lab(path, text, unit=unit, position=1)
        assert response.status_code == 400, (path, response.text)
        assert message in response.json()["detail"]
    with read_session() as db:
        assert db.exec(select(Take)).all() == []


def test_a_header_in_the_chosen_unit_is_read(lab):
    text = "Time (s),Rate (deg/s)\n" + "".join(
        f"{k * 0.5},{v / 3600.0!r}\n" for k, v in enumerate(HEADING[1])
    )
    preview = lab("/csv/preview", text, unit="deg/s", position=1).json()
    assert preview["positions"][0]["mean_deg_h"] == pytest.approx(np.mean(HEADING[1]))
