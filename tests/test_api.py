"""REST API v1 contract: every route, tokens, limits, atomicity and the CLI's schema."""

from __future__ import annotations

import json
from datetime import timedelta

import pytest
from sqlmodel import select

from app.core.sinusoid import heading_angles
from app.core.solve import solve_heading
from app.db import read_session, write_session
from app.models import ApiToken, Assignment, Role, SampleChunk, Take, utcnow
from app.web.workbooks import XLSX_MEDIA_TYPE
from tests.factories import (
    API,
    DATA,
    HEADING_KEYS,
    LATITUDE_KEYS,
    PASSWORD,
    PRACTICE,
    csrf_from,
    handout,
    login,
    make_course,
    make_user,
    new_api_session,
    post_form,
    token_for,
)


@pytest.fixture
def auth(client, student):
    return token_for(client, "student1")


def upload_handout(client, auth, session_id):
    for part, name in (("heading", "handout_horizontal.csv"), ("latitude", "handout_vertical.csv")):
        for k, values in handout(name).items():
            response = client.put(
                f"{API}/sessions/{session_id}/{part}/positions/{k}",
                json={"samples": values, "unit": "deg/h"},
                headers=auth,
            )
            assert response.status_code == 200, response.text


def test_token_me_and_errors(client, student, auth):
    me = client.get(f"{API}/me", headers=auth).json()
    assert me["username"] == "student1" and me["role"] == "student"
    assert client.get(f"{API}/me").status_code == 401
    assert client.get(f"{API}/me").json()["detail"] == "Not authenticated."
    chinese = client.get(f"{API}/me", headers={"Accept-Language": "zh-CN"}).json()
    assert chinese == {
        "detail": "未认证：请发送“Authorization: Bearer <令牌>”或先登录。",
        "key": "api.not_authenticated",
    }
    assert client.get(f"{API}/me", headers={"Authorization": "Bearer nope"}).status_code == 401
    wrong = client.post(f"{API}/auth/token", data={"username": "student1", "password": "x"})
    assert wrong.status_code == 401 and wrong.json()["detail"] == "Wrong username or password."


def test_token_endpoint_is_throttled_like_the_login_page(client, student):
    for i in range(5):
        client.post(f"{API}/auth/token", data={"username": "student1", "password": f"w{i}"})
    response = client.post(f"{API}/auth/token", data={"username": "student1", "password": PASSWORD})
    assert response.status_code == 429 and "Retry-After" in response.headers


def test_expired_login_token_is_refused(client, student, auth):
    with write_session() as db:
        record = db.exec(select(ApiToken)).one()
        record.expires_at = utcnow() - timedelta(seconds=1)
        db.add(record)
    assert client.get(f"{API}/me", headers=auth).status_code == 401


def test_tokens_are_stored_hashed(client, student, auth):
    raw = auth["Authorization"].split()[1]
    with read_session() as db:
        record = db.exec(select(ApiToken)).one()
    assert raw not in (record.token_hash, record.prefix) and record.prefix == raw[:10]


def test_whole_handout_via_the_api_equals_gyrolab_solve(client, auth):
    session_id = new_api_session(client, auth)
    upload_handout(client, auth, session_id)
    results = client.get(f"{API}/sessions/{session_id}/results", headers=auth).json()
    assert list(results["heading"]) == HEADING_KEYS
    assert list(results["latitude"]) == LATITUDE_KEYS
    expected = solve_heading(
        list(handout("handout_horizontal.csv").values()), heading_angles(4)
    ).to_json()
    assert results["heading"]["azimuth_deg"] == pytest.approx(expected["azimuth_deg"])
    assert results["latitude"]["latitude_error_percent"] == pytest.approx(2.00, abs=5e-3)
    detail = client.get(f"{API}/sessions/{session_id}", headers=auth).json()
    assert len(detail["positions"]) == 8 and detail["positions"][0]["source"] == "api"
    submitted = client.post(f"{API}/sessions/{session_id}/submit", headers=auth)
    assert submitted.status_code == 200 and submitted.json()["attempt"] == 1
    listed = client.get(f"{API}/sessions", headers=auth).json()
    assert [s["id"] for s in listed] == [session_id] and listed[0]["status"] == "submitted"


def test_results_carry_each_parts_data_quality_flags(client, auth):
    """A device that sends °/s as °/h learns it from the results, as the lab page says it;
    the handout's heading carries none (its vertical part a closure beyond 3σ)."""
    session_id = new_api_session(client, auth)
    upload_handout(client, auth, session_id)
    clean = client.get(f"{API}/sessions/{session_id}/results", headers=auth).json()
    assert "heading" not in clean["flags"]
    assert [flag["key"] for flag in clean["flags"]["latitude"]] == ["flag.closure"]
    for k, values in handout("handout_horizontal.csv").items():
        response = client.put(
            f"{API}/sessions/{session_id}/heading/positions/{k}",
            json={"samples": [v / 3600 for v in values], "unit": "deg/h"},
            headers=auth,
        )
        assert response.status_code == 200, response.text
    results = client.get(f"{API}/sessions/{session_id}/results", headers=auth).json()
    slip = results["flags"]["heading"][0]
    assert slip["key"] == "flag.unit_slip"
    assert slip["params"] == {"factor": "3600", "likely": "°/s", "chosen": "°/h"}
    assert "were they recorded in °/s and saved as °/h?" in slip["message"]


def test_results_are_null_without_enough_data(client, auth):
    session_id = new_api_session(client, auth)
    results = client.get(f"{API}/sessions/{session_id}/results", headers=auth).json()
    assert results["heading"] is None and results["latitude"] is None
    assert "at least 3 positions" in results["problems"]["heading"]


def test_csv_bodies(client, auth):
    session_id = new_api_session(client, auth)
    url = f"{API}/sessions/{session_id}/heading/positions/1"
    lines = "\n".join(str(v) for v in handout("handout_horizontal.csv")[1])
    response = client.put(url, content=lines, headers={**auth, "Content-Type": "text/csv"})
    assert response.status_code == 200 and response.json()["n_samples"] == 10
    timed = "time_s,value\n" + "\n".join(
        f"{i},{v}" for i, v in enumerate(handout("handout_horizontal.csv")[2])
    )
    response = client.put(
        f"{API}/sessions/{session_id}/heading/positions/2?unit=deg/h",
        content=timed,
        headers={**auth, "Content-Type": "text/csv"},
    )
    assert response.status_code == 200
    bad = client.put(url, content="1\n2\nthree\n", headers={**auth, "Content-Type": "text/csv"})
    assert bad.status_code == 400 and "Line 3" in bad.json()["detail"]
    # old Mac line ends (a bare CR) are lines too; an unreadable file is a 400, not a 500
    mac = client.put(
        url, content="\r".join(["1.5"] * 10), headers={**auth, "Content-Type": "text/csv"}
    )
    assert mac.status_code == 200 and mac.json()["n_samples"] == 10
    # a DOS program's file: CRLF lines and Ctrl-Z (0x1A) after the last, its end-of-file mark
    dos = client.put(
        url,
        content="\r\n".join(["1.5"] * 10) + "\r\n\x1a",
        headers={**auth, "Content-Type": "text/csv"},
    )
    assert dos.status_code == 200 and dos.json()["n_samples"] == 10
    huge = '"' + "9" * 200_000 + '"\n'
    unreadable = client.put(url, content=huge, headers={**auth, "Content-Type": "text/csv"})
    assert unreadable.status_code == 400 and "cannot be read" in unreadable.json()["detail"]


@pytest.mark.one_backend  # the body's parsing; storing is the same as for any CSV
def test_a_loggers_record_as_one_positions_csv(client, auth):
    """A script sends the gyro logger's own file: its clock in ns behind a '#' header with
    the unit -- read as the lab page reads it; a unit asked against the header refused."""
    from app.lab.samples import unpack

    session_id = new_api_session(client, auth)
    url = f"{API}/sessions/{session_id}/heading/positions/1"
    values = handout("handout_horizontal.csv")[1]
    text = "#timestamp [ns],rate [deg/h]\n" + "".join(
        f"{1_764_324_000_000_000_000 + k * 500_000_000},{v}\n" for k, v in enumerate(values)
    )
    csv = {**auth, "Content-Type": "text/csv"}
    refused = client.put(url + "?unit=deg/s", content=text, headers=csv)
    assert refused.status_code == 400 and "°/h, but °/s is chosen" in refused.json()["detail"]
    response = client.put(url + "?unit=deg/h", content=text, headers=csv)
    assert response.status_code == 200 and response.json()["n_samples"] == len(values)
    with read_session() as db:
        chunk = db.exec(select(SampleChunk)).first()
    assert unpack(chunk.times)[:3].tolist() == [0.0, 0.5, 1.0]
    assert unpack(chunk.values).tolist() == pytest.approx(values)


@pytest.mark.one_backend  # the body's parsing; storing is the same as for any CSV
def test_a_csv_body_is_read_as_the_lab_page_reads_a_file(client, auth):
    """Full-width digits and the minus sign "−" (a Chinese input method, a typeset handout)
    read as typed; a header or a row of units naming another unit than ``?unit=``, a
    Western Windows program's "°/s" included, refused and nothing stored; a clock coarser
    than the readings spread over its ticks; a first column that does not rise (a
    "1,234.5" under one name) no times but refused, not stored as time 1 and 234.5."""
    from app.lab.samples import unpack

    session_id = new_api_session(client, auth)
    url = f"{API}/sessions/{session_id}/heading/positions/1"
    csv = {**auth, "Content-Type": "text/csv"}
    values = handout("handout_horizontal.csv")[1]
    wide = str.maketrans("0123456789.-", "０１２３４５６７８９．－")
    typed = "\n".join(f"{v}".translate(wide) for v in values) + "\n−1.5\n"
    response = client.put(url, content=typed.encode(), headers=csv)
    assert response.status_code == 200, response.text
    with read_session() as db:
        chunk = db.exec(select(SampleChunk).order_by(SampleChunk.id.desc())).first()
    assert unpack(chunk.values).tolist() == pytest.approx([*values, -1.5])

    western = "Zeit [s];Drehrate [°/s]\r\n" + "\r\n".join(
        f"{k},0;{v / 3600:.9f}".replace(".", ",") for k, v in enumerate(values)
    )
    units_row = "time,rate\ns,deg/s\n" + "\n".join(f"{k},{v / 3600}" for k, v in enumerate(values))
    for body in (western.encode("cp1252"), units_row.encode()):
        refused = client.put(url + "?unit=deg/h", content=body, headers=csv)
        assert refused.status_code == 400 and refused.json()["key"] == "csv.unit_conflict"
        assert "°/s, but °/h is chosen" in refused.json()["detail"]
        response = client.put(url + "?unit=deg/s", content=body, headers=csv)
        assert response.status_code == 200, response.text
        with read_session() as db:
            chunk = db.exec(select(SampleChunk).order_by(SampleChunk.id.desc())).first()
        assert unpack(chunk.values).tolist() == pytest.approx(values, rel=1e-6)  # °/h

    ticks = "time_s,value\n" + "\n".join(f"{k // 2},{v}" for k, v in enumerate(values))
    response = client.put(url, content=ticks, headers=csv)
    assert response.status_code == 200, response.text
    with read_session() as db:
        chunk = db.exec(select(SampleChunk).order_by(SampleChunk.id.desc())).first()
    assert unpack(chunk.times)[:4].tolist() == [0.0, 0.5, 1.0, 1.5]
    for body in ("value\n" + "1,234.5\n" * 10, "time_s,value\n" + "".join(
        f"{10 - k},{v}\n" for k, v in enumerate(values))):  # fmt: skip
        refused = client.put(url, content=body, headers=csv)
        assert refused.status_code == 400, refused.text
    with read_session() as db:
        assert len(db.exec(select(SampleChunk)).all()) == 4  # the four saved above


@pytest.mark.one_backend  # the body's parsing; storing is the same as for any CSV
def test_one_axis_of_an_imus_record_is_the_column_the_script_names(client, auth):
    """An IMU's file of three gyro axes: refused without ``?column=`` (no axis guessed),
    read from the column named (its header cell or its number); a column it does not
    have, or an empty one, is a 400 that lists or says what to send."""
    from tests.test_position_record_files import imu_file

    session_id = new_api_session(client, auth)
    url = f"{API}/sessions/{session_id}/heading/positions/1?unit=rad/s"
    values = handout("handout_horizontal.csv")[1]
    csv = {**auth, "Content-Type": "text/csv"}
    text = imu_file(values)
    refused = client.put(url, content=text, headers=csv)
    assert refused.status_code == 400 and refused.json()["key"] == "csv.choose_column"
    assert "w_RS_S_z [rad s^-1]" in refused.json()["detail"]
    unknown = client.put(url + "&column=w_RS_S_q", content=text, headers=csv)
    assert unknown.status_code == 400 and unknown.json()["key"] == "allan.no_such_column"
    empty = client.put(url + "&column=", content=text, headers=csv)
    assert empty.status_code == 400 and empty.json()["key"] == "api.bad_column"
    from app.lab.samples import unpack

    for column in ("w_RS_S_z", "4"):
        response = client.put(url + f"&column={column}", content=text, headers=csv)
        assert response.status_code == 200 and response.json()["n_samples"] == len(values)
        with read_session() as db:
            chunk = db.exec(select(SampleChunk).order_by(SampleChunk.id.desc())).first()
        assert unpack(chunk.values).tolist() == pytest.approx(values)  # °/h, the z axis


@pytest.mark.one_backend  # the body's parsing; storing is the same as for any CSV
def test_a_phones_semicolon_export_is_saved_from_the_axis_named_with_its_times(client, auth):
    """phyphox's "CSV (Semicolon, decimal comma)": its quoted header's names were kept with
    their quotes, so the axis could not be named and "Time (s)" was offered as one."""
    from app.lab.samples import unpack
    from tests.test_imu_records import RATE_HZ, phyphox_text, white_rates

    session_id = new_api_session(client, auth)
    url = f"{API}/sessions/{session_id}/heading/positions/1?unit=rad/s"
    csv = {**auth, "Content-Type": "text/csv"}
    text = phyphox_text(";", ",")
    asked = client.put(url, content=text, headers=csv)
    assert asked.status_code == 400 and asked.json()["key"] == "csv.choose_column"
    assert '"Time (s)"' not in asked.json()["detail"]
    saved = client.put(url + "&column=Gyroscope z", content=text, headers=csv)
    assert saved.status_code == 200, saved.text
    with read_session() as db:
        chunk = db.exec(select(SampleChunk)).one()
    assert unpack(chunk.times)[:3] == pytest.approx([0.0, 1 / RATE_HZ, 2 / RATE_HZ])
    assert unpack(chunk.values) == pytest.approx(white_rates()[:, 2] * 3600.0, rel=1e-9)


@pytest.mark.one_backend  # the body's parsing
def test_a_table_of_every_position_sent_to_one_position_says_so(client, auth):
    """The handout's whole table PUT to one position's route was "Line 2: expected 'value'
    or 'time_s,value'"; it is named for what it is, with what to send instead."""
    session_id = new_api_session(client, auth)
    url = f"{API}/sessions/{session_id}/heading/positions/1"
    table = (DATA / "handout_horizontal.csv").read_bytes()
    for language, words in (("en", "a table of 4 positions"), ("zh-CN", "4 个位置的表格")):
        headers = {**auth, "Content-Type": "text/csv", "Accept-Language": language}
        refused = client.put(url, content=table, headers=headers)
        assert refused.status_code == 400 and refused.json()["key"] == "api.table_of_positions"
        assert words in refused.json()["detail"] and "/positions/4" in refused.json()["detail"]
    with read_session() as db:
        assert db.exec(select(SampleChunk)).all() == []


@pytest.mark.one_backend  # the body's parsing; storing is the same as for any CSV
@pytest.mark.parametrize(
    ("header", "first", "times", "temperatures"),
    [
        ("Time (ms),Rate (deg/h)", lambda k: f"{100 * k}", [0.0, 0.1, 0.2], None),
        ("Temp (C),Rate (deg/h)", lambda k: f"{25 + 0.01 * k:.2f}", None, [25.0, 25.01, 25.02]),
        ("Sample,Rate (deg/h)", lambda k: f"{k + 1}", None, None),
    ],
    ids=["ms", "a temperature", "a sample number"],
)
def test_a_two_column_records_header_says_what_its_first_column_is(
    client, auth, header, first, times, temperatures
):
    """Two columns were times in seconds and readings by their places, whatever the
    header said: milliseconds were seconds (a 10 Hz record stored at 0.01 Hz), a case
    temperature and a sample number were times.  They are read as the lab page reads
    the file."""
    from app.lab.samples import unpack

    session_id = new_api_session(client, auth)
    url = f"{API}/sessions/{session_id}/heading/positions/1?unit=deg/h"
    values = handout("handout_horizontal.csv")[1]
    text = header + "\n" + "".join(f"{first(k)},{v}\n" for k, v in enumerate(values))
    response = client.put(url, content=text, headers={**auth, "Content-Type": "text/csv"})
    assert response.status_code == 200, response.text
    with read_session() as db:
        chunk = db.exec(select(SampleChunk)).one()
    assert unpack(chunk.values).tolist() == values
    stored_times = None if chunk.times is None else unpack(chunk.times)[:3].tolist()
    assert stored_times == (None if times is None else pytest.approx(times))
    stored_temperatures = None if chunk.temperatures is None else unpack(chunk.temperatures)
    assert (None if stored_temperatures is None else stored_temperatures[:3].tolist()) == (
        None if temperatures is None else pytest.approx(temperatures)
    )


@pytest.mark.one_backend  # the body's parsing; storing is the same as for commas
@pytest.mark.parametrize(
    ("separator", "decimal"),
    [("\t", "."), (";", ","), ("\t", ",")],
    ids=["a spreadsheet's copy", "a European export", "tabs and decimal commas"],
)
def test_csv_bodies_separated_by_tabs_or_semicolons_read_as_the_lab_page_reads_them(
    client, auth, separator, decimal
):
    """What a spreadsheet puts on the clipboard (tabs) and what one in Europe saves (``;``,
    decimal commas) give the same readings, and so the same heading, as the comma CSV."""

    def heading_from(body_of) -> float:
        session_id = new_api_session(client, auth)
        for k, values in handout("handout_horizontal.csv").items():
            response = client.put(
                f"{API}/sessions/{session_id}/heading/positions/{k}?unit=deg/h",
                content=body_of(values).encode(),
                headers={**auth, "Content-Type": "text/csv"},
            )
            assert response.status_code == 200, response.text
            assert response.json()["n_samples"] == len(values)
        results = client.get(f"{API}/sessions/{session_id}/results", headers=auth).json()
        return results["heading"]["azimuth_deg"]

    def commas(values):
        return "time_s,value\n" + "\n".join(f"{i},{v!r}" for i, v in enumerate(values))

    def separated(values):
        rows = [f"{i}{separator}{v!r}".replace(".", decimal) for i, v in enumerate(values)]
        return f"time_s{separator}value\r\n" + "\r\n".join(rows)

    assert heading_from(separated) == heading_from(commas)


@pytest.mark.one_backend  # input refused before any write
@pytest.mark.parametrize(
    ("body", "status", "text"),
    [
        ({"samples": [True] * 10}, 422, ""),
        ({"samples": ["1.0"] * 10}, 422, ""),
        ({"samples": []}, 422, ""),
        ({"samples": [1.0] * 10, "unit": "furlong/h"}, 422, ""),
        ({"samples": [1.0] * 5}, 400, "at least 10"),
        ({"samples": [1.0] * 10, "times_s": [0.0] * 9}, 400, "one entry per sample"),
        ({"samples": [1.0] * 10, "unit": "deg/s"}, 200, ""),
        ({"samples": [3.0] * 10, "unit": "deg/s"}, 400, "check the unit"),
        # the aliases ?unit= and the pages take: "dps" is °/s (so 3 of it is no Earth rate)
        ({"samples": [1.0] * 10, "unit": "°/h"}, 200, ""),
        ({"samples": [1.0] * 10, "unit": "dph"}, 200, ""),
        ({"samples": [3.0] * 10, "unit": "dps"}, 400, "check the unit"),
        ({"samples": [3.0] * 10, "unit": " °/s "}, 400, "check the unit"),
        ({"samples": [1.0] * 10, "unit": 3}, 422, ""),
    ],
)
def test_strict_validation(client, auth, body, status, text):
    session_id = new_api_session(client, auth)
    response = client.put(
        f"{API}/sessions/{session_id}/heading/positions/1", json=body, headers=auth
    )
    assert response.status_code == status, response.text
    if text:
        assert text in response.json()["detail"]


@pytest.mark.one_backend  # input refused before any write
def test_a_misspelt_field_is_said_not_dropped(client, auth):
    """A field the API does not know is refused with its place (422), never dropped: a
    dropped ``"units": "rad/s"`` stored rad/s as °/h, a dropped ``"start_angle"`` put every
    dial angle 45° off, a dropped ``"symmetric"`` recorded four positions, not eight."""
    session_id = new_api_session(client, auth)
    sent = [
        ("POST", f"{API}/sessions", {"station": {"latitude_deg": 39.93}, "symmetric": True}),
        (
            "POST",
            f"{API}/sessions",
            {"station": {"latitude_deg": 39.93}, "heading": {"start_angle": 45}},
        ),
        ("POST", f"{API}/sessions", {"station": {"latitude_deg": 39.93, "rate": 15.04}}),
        (
            "PUT",
            f"{API}/sessions/{session_id}/heading/positions/1",
            {"samples": [1e-5] * 10, "units": "rad/s"},
        ),
        ("PUT", f"{API}/sessions/{session_id}/heading/positions/1/trim", {"trim": 1, "n": 2}),
    ]
    places = [
        ["body", "symmetric"],
        ["body", "heading", "start_angle"],
        ["body", "station", "rate"],
        ["units"],
        ["body", "n"],
    ]
    for (method, url, body), place in zip(sent, places, strict=True):
        for language, message in (
            ("en", "Not a field of this request."),
            ("zh-CN", "本请求没有这个字段。"),
        ):
            response = client.request(
                method, url, json=body, headers={**auth, "Accept-Language": language}
            )
            assert response.status_code == 422, response.text
            assert response.json()["detail"] == [
                {"loc": place, "msg": message, "type": "extra_forbidden"}
            ]
    with read_session() as db:
        assert db.exec(select(Take)).first() is None


def test_non_finite_samples_store_nothing(client, auth):
    session_id = new_api_session(client, auth)
    body = '{"samples": [1.0, 2.0, NaN, 4, 5, 6, 7, 8, 9, 10]}'
    response = client.put(
        f"{API}/sessions/{session_id}/heading/positions/1",
        content=body,
        headers={**auth, "Content-Type": "application/json"},
    )
    assert response.status_code == 400 and "finite" in response.json()["detail"]
    with read_session() as db:
        assert db.exec(select(Take)).first() is None
        assert db.exec(select(SampleChunk)).first() is None
    response = client.put(
        f"{API}/sessions/{session_id}/heading/positions/1",
        content="{oops",
        headers={**auth, "Content-Type": "application/json"},
    )
    assert response.status_code == 400


def test_append_with_offsets_is_idempotent(client, auth):
    session_id = new_api_session(client, auth)
    url = f"{API}/sessions/{session_id}/latitude/positions/3/samples"
    first = client.post(url, json={"samples": [1.0, 2.0, 3.0], "offset": 0}, headers=auth)
    assert first.json() == {
        "session_id": session_id,
        "part": "latitude",
        "position": 3,
        "n_samples": 3,
        "added": 3,
    }
    again = client.post(url, json={"samples": [1.0, 2.0, 3.0], "offset": 0}, headers=auth)
    assert again.json()["n_samples"] == 3 and again.json()["added"] == 0  # a retry
    overlap = client.post(url, json={"samples": [3.0, 4.0, 5.0], "offset": 2}, headers=auth)
    assert overlap.json()["n_samples"] == 5 and overlap.json()["added"] == 2
    gap = client.post(url, json={"samples": [9.0], "offset": 7}, headers=auth)
    assert gap.status_code == 409 and "Expected offset 5" in gap.json()["detail"]
    with read_session() as db:
        take = db.exec(select(Take)).one()
        from app.lab.store import load_samples

        assert load_samples(db, take)[0].tolist() == [1.0, 2.0, 3.0, 4.0, 5.0]


@pytest.mark.parametrize(
    ("times", "reading", "at", "before"),
    [
        ([0.0] * 10, 2, "0", "0"),  # a clock that never ran
        (list(range(10, 0, -1)), 2, "9", "10"),  # run backwards
        ([*range(5), *range(5)], 6, "0", "4"),  # two recordings run together
        ([0.0, 0.1, 0.2, 0.3, 0.4, 0.45, 0.4, 0.7, 0.8, 0.9], 7, "0.4", "0.45"),  # set back
    ],
)
def test_sample_times_that_do_not_rise_are_refused_whatever_brings_them(
    client, auth, times, reading, at, before
):
    """The drift fit and the warm-up check read a position's times as one clock: times
    that stand still or go back are refused, as JSON, as raw float64 pairs and as ``.npy``
    (the CSV reader already refused them as not one position's record), naming the
    reading, in both languages; nothing is stored."""
    import io

    import numpy as np

    session_id = new_api_session(client, auth)
    url = f"{API}/sessions/{session_id}/heading/positions/1"
    values = [10.0 + 0.01 * k for k in range(10)]
    pairs = np.column_stack([times, values]).astype("<f8")
    npy = io.BytesIO()
    np.save(npy, pairs)
    binary = {"Content-Type": "application/octet-stream"}
    sent = [
        client.put(url, json={"samples": values, "times_s": times}, headers=auth),
        client.put(url, content=pairs.tobytes(), params={"columns": 2}, headers={**auth, **binary}),
        client.put(url, content=npy.getvalue(), headers={**auth, **binary}),
    ]
    for response in sent:
        assert response.status_code == 400, response.text
        assert response.json()["key"] == "lab.times_not_rising"
        assert response.json()["detail"] == (
            f"Position 1: the sample times must rise, each later than the one before, but "
            f"reading {reading} is at {at} s and the one before it at {before} s. Was the "
            "clock set back, or were two recordings run together? Send each recording on "
            "its own, or send no times."
        )
    chinese = client.put(
        url,
        json={"samples": values, "times_s": times},
        headers={**auth, "Accept-Language": "zh-CN"},
    )
    assert chinese.json()["detail"].startswith(
        f"位置 1：采样时间须逐个递增，但第 {reading} 个读数的时间 {at} s "
        f"不晚于前一个的 {before} s。"
    )
    with read_session() as db:
        assert db.exec(select(Take)).first() is None
    rising = client.put(url, json={"samples": values, "times_s": list(range(10))}, headers=auth)
    assert rising.status_code == 200


def test_an_append_carries_its_times_on_from_those_stored(client, auth):
    """A streaming device's batches are one recording: each batch's times rise from the last
    one stored; a clock restarted between batches is refused, the reading named by its
    number in the position; a retried batch (the same offset) is still stored once."""
    session_id = new_api_session(client, auth)
    url = f"{API}/sessions/{session_id}/heading/positions/2/samples"

    def post(samples, times, offset, language="en"):
        body = {"samples": samples, "times_s": times, "offset": offset}
        return client.post(url, json=body, headers={**auth, "Accept-Language": language})

    assert post([1.0, 2.0, 3.0], [0.0, 0.1, 0.2], 0).json()["added"] == 3
    assert post([1.0, 2.0, 3.0], [0.0, 0.1, 0.2], 0).json()["added"] == 0  # a retry
    restarted = post([4.0, 5.0], [0.0, 0.1], 3)
    assert restarted.status_code == 400 and restarted.json()["key"] == "lab.times_not_after"
    assert restarted.json()["detail"] == (
        "Position 2: this batch's first time, 0 s, is not after the last one stored, 0.2 s. "
        "One recording's times run on from batch to batch."
    )
    assert post([4.0, 5.0], [0.2, 0.3], 3, "zh-CN").json()["detail"] == (
        "位置 2：这批读数的第一个时间 0.2 s 不晚于已保存的最后一个时间 0.2 s。"
        "同一段记录的时间应一批接一批向后递增。"
    )
    inside = post([4.0, 5.0], [0.4, 0.3], 3)
    assert inside.json()["key"] == "lab.times_not_rising"
    assert "reading 5 is at 0.3 s and the one before it at 0.4 s" in inside.json()["detail"]
    assert post([4.0, 5.0], [0.3, 0.4], 3).json()["n_samples"] == 5
    with read_session() as db:
        from app.lab.store import load_samples

        values, times = load_samples(db, db.exec(select(Take)).one())[:2]
        assert values.tolist() == [1.0, 2.0, 3.0, 4.0, 5.0]
        assert times.tolist() == [0.0, 0.1, 0.2, 0.3, 0.4]


def test_objects_of_others_answer_404(client, app, student, auth):
    from fastapi.testclient import TestClient

    session_id = new_api_session(client, auth)
    make_user("other", Role.student)
    with TestClient(app) as other_client:
        other = token_for(other_client, "other")
        base = f"{API}/sessions/{session_id}"
        assert other_client.get(base, headers=other).status_code == 404
        assert other_client.get(f"{base}/results", headers=other).status_code == 404
        assert (
            other_client.put(
                f"{base}/heading/positions/1", json={"samples": [1.0] * 10}, headers=other
            ).status_code
            == 404
        )
        assert other_client.post(f"{base}/submit", headers=other).status_code == 404
        assert other_client.get(f"{API}/courses", headers=other).status_code == 403


def test_personal_tokens_page_scopes_and_revocation(client, student):
    login(client, "student1")
    page = post_form(
        client,
        "/account/tokens",
        {"name": "bench bridge", "scopes": ["read"]},
        page="/account/tokens",
    )
    assert page.status_code == 200 and "shown only now" in page.text
    raw = page.text.split('id="new-token">')[1].split("<")[0]
    headers = {"Authorization": f"Bearer {raw}"}
    client.cookies.clear()
    assert client.get(f"{API}/me", headers=headers).status_code == 200
    denied = client.post(f"{API}/sessions", json=PRACTICE, headers=headers)
    assert denied.status_code == 403 and "'upload' scope" in denied.json()["detail"]
    login(client, "student1")
    listing = client.get("/account/tokens").text
    assert "bench bridge" in listing and raw not in listing and raw[:10] in listing
    with read_session() as db:
        token_id = db.exec(select(ApiToken)).one().id
    post_form(client, f"/account/tokens/{token_id}/revoke", page="/account/tokens")
    client.cookies.clear()
    assert client.get(f"{API}/me", headers=headers).status_code == 401


def test_rate_limit_per_token(client, student, auth, monkeypatch):
    from app.config import get_settings

    monkeypatch.setattr(get_settings(), "api_rate_per_minute", 3)
    statuses = [client.get(f"{API}/me", headers=auth).status_code for _ in range(5)]
    assert statuses == [200, 200, 200, 429, 429]


def test_cookie_requests_need_the_csrf_header(client, student):
    login(client, "student1")
    assert client.get(f"{API}/me").status_code == 200
    assert client.post(f"{API}/sessions", json=PRACTICE).status_code == 403
    token = csrf_from(client, "/lab")
    response = client.post(f"{API}/sessions", json=PRACTICE, headers={"X-CSRF-Token": token})
    assert response.status_code == 201


def test_bearer_requests_need_no_csrf(client, auth):
    assert client.post(f"{API}/sessions", json=PRACTICE, headers=auth).status_code == 201


def test_teacher_routes(client, app, teacher):
    from fastapi.testclient import TestClient

    student = make_user("s1", Role.student, name="张三")
    course_id = make_course(teacher, "Nav 惯导", (student,))
    with write_session() as db:
        assignment = Assignment(
            course_id=course_id,
            title="Find north",
            latitude_deg=39.93,
            earth_rate_deg_h=15.04,
            allowed_methods="manual,csv",
        )
        db.add(assignment)
        db.flush()
        assignment_id = assignment.id
    with TestClient(app) as student_client:
        student_auth = token_for(student_client, "s1")
        body = {"assignment_id": assignment_id}
        session_id = new_api_session(student_client, student_auth, body)
        again = student_client.post(f"{API}/sessions", json=body, headers=student_auth)
        assert again.status_code == 200 and again.json()["id"] == session_id
        upload_handout(student_client, student_auth, session_id)
        student_client.post(f"{API}/sessions/{session_id}/submit", headers=student_auth)
        assert (
            student_client.get(
                f"{API}/assignments/{assignment_id}/submissions", headers=student_auth
            ).status_code
            == 403
        )
    teacher_auth = token_for(client, "teacher1")
    courses = client.get(f"{API}/courses", headers=teacher_auth).json()
    assert courses[0]["assignments"][0]["id"] == assignment_id
    rows = client.get(f"{API}/assignments/{assignment_id}/submissions", headers=teacher_auth).json()
    assert rows[0]["display_name"] == "张三" and rows[0]["status"] == "submitted"
    assert rows[0]["latitude_error_percent"] == pytest.approx(2.00, abs=5e-3)
    exported = client.get(f"{API}/assignments/{assignment_id}/export.csv", headers=teacher_auth)
    assert exported.content.startswith("\ufeff".encode()) and "张三" in exported.text
    make_user("t2", Role.teacher)
    with TestClient(app) as other:
        other_auth = token_for(other, "t2")
        assert (
            other.get(
                f"{API}/assignments/{assignment_id}/submissions", headers=other_auth
            ).status_code
            == 404
        )


def test_must_change_password_users_get_no_token(client):
    make_user("fresh", Role.student, must_change=True)
    response = client.post(f"{API}/auth/token", data={"username": "fresh", "password": PASSWORD})
    assert response.status_code == 403


def test_openapi_documents_every_route(client):
    schema = client.get("/openapi.json").json()
    paths = schema["paths"]
    assert len(paths) == 20
    for path, operations in paths.items():
        for method, operation in operations.items():
            assert operation.get("summary"), (method, path)
            assert "401" in operation["responses"] or path.endswith("/auth/token")
    upload = paths[f"{API}/sessions/{{session_id}}/{{part}}/positions/{{position}}"]["put"]
    assert set(upload["requestBody"]["content"]) == {
        "application/json",
        "text/csv",
        "application/octet-stream",
    }
    table = paths[f"{API}/assignments/{{assignment_id}}/export.xlsx"]["get"]["responses"]["200"]
    assert set(table["content"]) == {XLSX_MEDIA_TYPE}
    docs = client.get("/docs")
    assert docs.status_code == 200 and "/vendor/swagger-ui/swagger-ui-bundle.js" in docs.text
    assert "cdn" not in docs.text.lower()
    assert client.get("/vendor/swagger-ui/swagger-ui-bundle.js").status_code == 200
    for_swagger_ui = client.get("/docs/openapi.json").json()  # Swagger UI 4 reads 3.0 only
    assert for_swagger_ui["openapi"].startswith("3.0") and for_swagger_ui["paths"] == paths


def test_oversized_body_is_refused(client, auth):
    session_id = new_api_session(client, auth)
    body = json.dumps({"samples": [1.0] * 10}) + " " * (33 * 1024 * 1024)
    response = client.put(
        f"{API}/sessions/{session_id}/heading/positions/1",
        content=body,
        headers={**auth, "Content-Type": "application/json"},
    )
    assert response.status_code == 413


def test_symmetric_order_over_the_api(client, auth):
    """Positions 5–8 exist only in the symmetric order; there they revisit 4–1 and, sent
    with times, let the fit estimate a linear drift."""
    plain = new_api_session(client, auth)
    reply = client.put(
        f"{API}/sessions/{plain}/heading/positions/5", json={"samples": [1.0] * 10}, headers=auth
    )
    assert reply.status_code == 400 and "symmetric" in reply.json()["detail"]
    session_id = new_api_session(client, auth, {**PRACTICE, "symmetric_order": True})
    assert client.get(f"{API}/sessions/{session_id}", headers=auth).json()["symmetric_order"]
    drift = 3.0  # °/h per hour
    truth = [10.71, 2.79, -8.95, -0.94]
    for k in range(1, 9):
        times = [120.0 * (k - 1) + t for t in range(10)]
        mean = truth[k - 1 if k <= 4 else 8 - k] + drift * (sum(times) / 10) / 3600
        reply = client.put(
            f"{API}/sessions/{session_id}/heading/positions/{k}",
            json={"samples": [mean] * 10, "times_s": times},
            headers=auth,
        )
        assert reply.status_code == 200, reply.text
    heading = client.get(f"{API}/sessions/{session_id}/results", headers=auth).json()["heading"]
    assert heading["n_positions"] == 8
    assert heading["drift_deg_h_per_h"] == pytest.approx(drift, rel=1e-6)
    assert heading["theta_deg"] == pytest.approx(-10.743, abs=1e-3)  # the printed averages


def test_a_flags_parameter_may_be_empty():
    """The warm-up flag of a gyro already warm names no minutes (None): still a valid body."""
    from app.core.drift_check import warm_up_message
    from app.lab.schemas import ResultsOut

    class Warm:
        wait_minutes = None
        shift = None

    key, params = warm_up_message(Warm())
    assert params == {"minutes": None}
    body = {"heading": None, "latitude": None, "flags": {"heading": [
        {"key": key, "params": params, "message": "the gyro was still warming up"}
    ]}}  # fmt: skip
    assert ResultsOut.model_validate(body).flags["heading"][0].params == {"minutes": None}
