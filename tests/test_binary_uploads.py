"""Binary uploads: raw little-endian float64/float32 and .npy files on the position routes,
stored exactly as JSON would store them."""

from __future__ import annotations

import io
import json

import numpy as np
import pytest
from sqlmodel import select

from app.db import read_session
from app.lab.exports import Selection, readings_csv, session_json
from app.lab.result_flags import quality_flags
from app.lab.results import current_data
from app.lab.samples import unpack
from app.lab.store import load_samples
from app.models import LabSession, SampleChunk, Take
from tests.factories import API, handout, new_api_session, token_for


@pytest.fixture
def auth(client, student):
    return token_for(client, "student1")


def put_binary(client, auth, session_id, body: bytes, position=1, **params):
    return client.put(
        f"{API}/sessions/{session_id}/heading/positions/{position}",
        content=body,
        params=params,
        headers={**auth, "Content-Type": "application/octet-stream"},
    )


def npy(array: np.ndarray) -> bytes:
    buffer = io.BytesIO()
    np.save(buffer, array, allow_pickle=False)
    return buffer.getvalue()


def npy_claiming(shape: tuple, descr: str = "<f8", data: bytes = b"\x00" * 64) -> bytes:
    """A ``.npy`` file (NEP 1, version 1.0) whose header claims ``shape``, before ``data``."""
    header = f"{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape!r}, }}"
    header += " " * (-(10 + len(header) + 1) % 64) + "\n"
    return b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header.encode() + data


def stored(session_id: int, position: int = 1) -> tuple[np.ndarray, np.ndarray | None]:
    with read_session() as db:
        take = db.exec(
            select(Take).where(
                Take.session_id == session_id,
                Take.position == position,
                Take.superseded_at.is_(None),
            )
        ).one()
        return load_samples(db, take)


def test_every_binary_form_stores_the_same_samples(client, auth):
    columns = handout("handout_horizontal.csv")
    values = np.array(columns[1])
    times = np.arange(values.size) * 0.1 + 5.0
    forms = [
        (values.astype("<f8").tobytes(), {}),
        (values.astype("<f4").tobytes(), {"dtype": "float32"}),
        (np.column_stack([times, values]).astype("<f8").tobytes(), {"columns": "2"}),
        (npy(values), {}),
        (npy(values.astype(">f8")), {}),  # big-endian .npy: its header says so
        (npy(np.column_stack([times, values])), {}),
        (npy(np.round(values * 100).astype(np.int32)), {"unit": "deg/h"}),
    ]
    for body, params in forms:
        session_id = new_api_session(client, auth)
        response = put_binary(client, auth, session_id, body, **params)
        assert response.status_code == 200, (params, response.text)
        got, got_times = stored(session_id)
        if body == forms[-1][0]:
            np.testing.assert_allclose(got, np.round(values * 100))
        else:
            np.testing.assert_allclose(got, values, rtol=1e-6 if "dtype" in params else 0)
        if params.get("columns") or body in (forms[5][0],):
            np.testing.assert_array_equal(got_times, times)


def test_units_angle_and_appends_ride_in_the_query(client, auth):
    session_id = new_api_session(client, auth)
    values = np.full(10, 0.001)
    response = put_binary(
        client, auth, session_id, values.tobytes(), unit="deg/s", angle_deg="-90", position=2
    )
    assert response.status_code == 200
    np.testing.assert_allclose(stored(session_id, 2)[0], 3.6)
    url = f"{API}/sessions/{session_id}/heading/positions/3/samples"
    headers = {**auth, "Content-Type": "application/octet-stream"}
    for offset in (0, 0, 5):  # the repeated batch is stored once
        batch = np.full(5, 10.0 + offset).tobytes()
        reply = client.post(url, content=batch, params={"offset": offset}, headers=headers)
        assert reply.status_code == 200, reply.text
    assert reply.json()["n_samples"] == 10


@pytest.mark.one_backend  # input refused before any write
@pytest.mark.parametrize(
    ("body", "params", "message"),
    [
        (b"\x00" * 12, {}, "not a whole number of 8-byte samples"),
        (b"\x00" * 16, {"dtype": "complex128"}, "Unknown dtype"),
        (b"\x00" * 16, {"columns": "4"}, "columns must be 1"),
        (b"\x00" * 32, {"columns": "3"}, "not a whole number of 24-byte samples"),
        (b"", {}, "no samples"),
        (np.array([1.0, np.nan]).tobytes(), {}, "finite"),
        (np.array([1.0, np.inf]).astype("<f4").tobytes(), {"dtype": "float32"}, "finite"),
        (npy(np.zeros((2, 2, 2))), {}, "shape (2, 2, 2)"),
        (npy(np.array(["a", "b"])), {}, "not a readable .npy"),
        (b"\x93NUMPY\x01\x00garbage", {}, "not a readable .npy"),
        # headers np.load believed: a 500 (MemoryError: 10¹² numbers set aside for 64
        # bytes; a TokenError for a header that is no literal) -- now checked first
        (npy_claiming((10**12,)), {}, "not a readable .npy"),
        (npy_claiming((10**8, 2)), {}, "not a readable .npy"),
        (b"\x93NUMPY\x01\x00\x10\x00{'descr': __import__('os')}\n", {}, "not a readable .npy"),
        (npy_claiming((-5,)), {}, "not a readable .npy"),
        (npy_claiming((4,), descr="<c16"), {}, "not a readable .npy"),
        (np.ones(10).tobytes(), {"offset": "-1"}, "offset must be"),
    ],
)
def test_bad_binary_bodies_are_explained_and_store_nothing(client, auth, body, params, message):
    session_id = new_api_session(client, auth)
    response = put_binary(client, auth, session_id, body, **params)
    assert 400 <= response.status_code < 500, response.text
    assert message in str(response.json()["detail"])
    with read_session() as db:
        assert db.exec(select(Take).where(Take.session_id == session_id)).all() == []


def test_a_pickled_npy_is_never_loaded(client, auth):
    buffer = io.BytesIO()
    np.save(buffer, np.array([{"x": 1}], dtype=object), allow_pickle=True)
    session_id = new_api_session(client, auth)
    response = put_binary(client, auth, session_id, buffer.getvalue())
    assert response.status_code == 400 and response.json()["key"] == "api.bad_npy"


def test_the_bridge_uploads_binary(client, auth):
    """gyrolab bridge's uploader sends raw float64 by default (8 bytes a reading)."""
    from app.bridge.upload import Uploader

    session_id = new_api_session(client, auth)
    client.headers.update(auth)
    uploader = Uploader(client, session_id, "heading", 1, batch=4)
    sent = []
    original = client.post

    def spy(url, **kwargs):
        sent.append(kwargs)
        return original(url, **kwargs)

    client.post = spy
    for value in range(10):
        uploader.add(10.0 + value)
    uploader.flush()
    assert uploader.sent == 10
    assert all(k["headers"]["Content-Type"] == "application/octet-stream" for k in sent)
    np.testing.assert_array_equal(stored(session_id)[0], 10.0 + np.arange(10))


def test_gyro_temperatures_are_stored_exported_and_flag_a_warm_up(client, auth):
    """What the bridge sends from a KVH or a described frame: time, value, temperature."""
    session_id = new_api_session(client, auth)
    n = 40
    times = 100.0 + np.arange(n) * 0.01
    values = np.full(n, 10.0)
    temperatures = 25.0 + np.linspace(0.0, 2.0, n)  # still warming up: 2 °C
    url = f"{API}/sessions/{session_id}/heading/positions/1/samples"
    binary = {**auth, "Content-Type": "application/octet-stream"}
    triples = np.column_stack([times, values, temperatures]).astype("<f8")
    first = client.post(
        url, content=triples[:20].tobytes(), params={"columns": "3", "offset": "0"}, headers=binary
    )
    assert first.status_code == 200, first.text
    second = client.post(
        url,
        json={
            "samples": values[20:].tolist(),
            "times_s": times[20:].tolist(),
            "temperatures_c": temperatures[20:].tolist(),
            "offset": 20,
        },
        headers=auth,
    )
    assert second.json()["n_samples"] == n
    refusals = [
        ({"samples": [10.0], "times_s": [101.0], "offset": n}, "lab.temperatures_mismatch"),
        (
            {"samples": [10.0, 10.0], "temperatures_c": [20.0], "offset": n},
            "api.temperatures_count",
        ),
        (
            {"samples": [10.0], "times_s": [101.0], "temperatures_c": [1e6], "offset": n},
            "lab.bad_temperatures",
        ),
    ]
    for body, key in refusals:
        refused = client.post(url, json=body, headers=auth)
        assert refused.status_code == 400 and refused.json()["key"] == key, refused.text
    with read_session() as db:
        session = db.get(LabSession, session_id)
        chunks = db.exec(
            select(SampleChunk)
            .join(Take, Take.id == SampleChunk.take_id)
            .where(Take.session_id == session_id)
            .order_by(SampleChunk.seq)
        ).all()
        flags = quality_flags(session, current_data(db, session)["heading"])
    assert np.concatenate([unpack(c.temperatures) for c in chunks]) == pytest.approx(temperatures)
    assert {"key": "flag.warm_up", "params": {"position": 1, "change": "2.0"}} in flags
    table = "".join(readings_csv(Selection(session_id)))
    assert "source,time_s,value,temperature_c\n" in table
    assert "heading,1,0,api,100.390,10.000000,27.00\n" in table
    exported = json.loads("".join(session_json(Selection(session_id))))
    assert exported["positions"][0]["temperatures_c"] == pytest.approx(temperatures)
    assert exported["positions"][0]["times_s"] == pytest.approx(times)


def test_a_npy_in_any_byte_order_and_layout_is_read_as_saved(client, auth):
    """Big-endian integers, Fortran-ordered time and value rows, half precision: read
    from the file's own bytes as np.load reads them."""
    session_id = new_api_session(client, auth)
    rows = np.column_stack([0.5 * np.arange(12), 10.0 + np.arange(12)])
    for position, array in enumerate(
        [np.arange(10, 22, dtype=">i4"), np.asfortranarray(rows), rows.astype("<f2")], start=1
    ):
        assert put_binary(client, auth, session_id, npy(array), position).status_code == 200
    values, times = stored(session_id, 1)
    np.testing.assert_array_equal(values, np.arange(10, 22))
    for position in (2, 3):
        values, times = stored(session_id, position)
        np.testing.assert_array_equal(values, 10.0 + np.arange(12))
        np.testing.assert_array_equal(times, 0.5 * np.arange(12))


def test_a_npy_of_one_or_three_columns_is_read_as_the_raw_columns_are(client, auth):
    """A column vector ``(n, 1)`` is the values; ``(n, 3)`` is time, value and temperature,
    as ``?columns=3`` reads raw floats and the lab page reads such a ``.npy`` -- both were
    refused by shape."""
    session_id = new_api_session(client, auth)
    times = 2.0 + 0.1 * np.arange(12)
    values = 10.0 + 0.01 * np.arange(12)
    temperatures = 25.0 + 0.05 * np.arange(12)
    column = put_binary(client, auth, session_id, npy(values[:, None]), 1)
    assert column.status_code == 200, column.text
    assert stored(session_id, 1)[0].tolist() == values.tolist()
    triples = np.column_stack([times, values, temperatures])
    saved = put_binary(client, auth, session_id, npy(triples), 2)
    assert saved.status_code == 200, saved.text
    got_values, got_times = stored(session_id, 2)
    assert got_values.tolist() == values.tolist() and got_times.tolist() == times.tolist()
    with read_session() as db:
        take = db.exec(select(Take).where(Take.session_id == session_id, Take.position == 2)).one()
        chunk = db.exec(select(SampleChunk).where(SampleChunk.take_id == take.id)).one()
    assert unpack(chunk.temperatures).tolist() == temperatures.tolist()
    hot = triples.copy()
    hot[3, 2] = 1e6  # a temperature no gyro has: refused as the JSON's and raw's are
    refused = put_binary(client, auth, session_id, npy(hot), 3)
    assert refused.status_code == 400 and refused.json()["key"] == "lab.bad_temperatures"
    four = put_binary(client, auth, session_id, npy(np.ones((5, 4))), 3)
    assert four.status_code == 400 and "(n, 3)" in four.json()["detail"]
