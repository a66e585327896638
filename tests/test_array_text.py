"""A MATLAB or NumPy file of one position's record on the lab page's file panel: its
vectors read as a record's text (the times its own or its sample rate's), previewed,
saved with the file's own numbers, and refused in words where it holds no record.  The
files are written here by scipy.io.savemat and numpy, the readings drawn from the tests'
own generator."""

from __future__ import annotations

import io
import math

import numpy as np
import pytest
import scipy.io
from sqlmodel import select

from app.core.array_text import MAX_NUMBERS, array_file_text, is_array_file
from app.core.exceptions import UserError
from app.db import read_session
from app.lab.samples import unpack
from app.models import SampleChunk, Take
from tests.factories import _form_token, handout, login, new_session, post_json
from tests.noise_sources import static_record

pytestmark = pytest.mark.one_backend  # the reading is new; the saving is the CSV method's

RAD_S = math.radians(1.0) / 3600.0  # 1 °/h in rad/s


def mat_file(**variables) -> bytes:
    buffer = io.BytesIO()
    scipy.io.savemat(buffer, variables)
    return buffer.getvalue()


def npy_file(array: np.ndarray) -> bytes:
    buffer = io.BytesIO()
    np.save(buffer, array)
    return buffer.getvalue()


def omega(count: int = 300, seed: int = 1) -> np.ndarray:
    """A static FOG's rate in rad/s about 10 °/h (the independent generator's white noise)."""
    return static_record(count / 3600.0, 1.0, arw=0.01, seed=seed) * RAD_S


@pytest.fixture
def lab(client, student):
    assert login(client, "student1").status_code == 303
    session_id = new_session(client)
    page = f"/lab/sessions/{session_id}"
    token = _form_token(client, page)

    def as_text(data: bytes, status: int = 200) -> dict:
        response = client.post(
            f"{page}/csv/binary",
            content=data,
            headers={
                "Content-Type": "application/octet-stream",
                "Accept": "application/json",
                "X-CSRF-Token": token,
            },
        )
        assert response.status_code == status, response.text
        return response.json()

    def send(path: str, text: str, **extra):
        body = {"part": "heading", "unit": "rad/s", "text": text, **extra}
        return post_json(client, page + path, body, page)

    send.page = page  # the session's page
    return client, as_text, send


def stored() -> tuple[Take, np.ndarray, np.ndarray | None]:
    with read_session() as db:
        [take] = db.exec(select(Take)).all()
        chunk = db.exec(select(SampleChunk)).one()
    return take, unpack(chunk.values), unpack(chunk.times) if chunk.times else None


def test_a_matlab_record_with_its_times_is_previewed_and_saved_as_the_files_numbers(lab):
    """MATLAB's own layout: ``t`` and ``omega`` in rad/s.  Saved at the position chosen,
    every reading the file's own (in °/h), its times the file's."""
    _, as_text, send = lab
    rates = omega()
    times = 0.01 * np.arange(rates.size)
    text = as_text(mat_file(t=times, omega=rates))["text"]
    assert text.startswith("#time (s)\tomega\n0.0\t")
    preview = send("/csv/preview", text).json()
    assert preview["layout"] == "record"
    [row] = preview["positions"]
    assert row["n"] == rates.size
    assert row["mean_deg_h"] == pytest.approx(np.mean(rates) / RAD_S, rel=1e-12)
    saved = send("/csv", text, position=3)
    assert saved.status_code == 200 and saved.json()["saved"] == [3]
    take, values, stored_times = stored()
    assert (take.position, take.n_samples) == (3, rates.size)
    np.testing.assert_allclose(values, rates / RAD_S, rtol=1e-14)
    np.testing.assert_array_equal(stored_times, times)


def test_an_imus_matrix_and_its_rate_offer_the_axes_and_save_the_one_chosen(lab):
    """A struct of an IMU's three axes (``imu.gyro``, n × 3) and ``imu.fs``: the times are
    the rate's (k / fs), the axes offered by name, the one chosen saved."""
    _, as_text, send = lab
    axes = np.column_stack([omega(seed=seed) for seed in (2, 3, 4)])
    text = as_text(mat_file(imu={"gyro": axes, "fs": 50.0}))["text"]
    assert text.splitlines()[0] == "#time (s)\timu.gyro 1\timu.gyro 2\timu.gyro 3"
    preview = send("/csv/preview", text).json()
    assert preview["columns"] and preview["column"] in [c["value"] for c in preview["columns"]]
    chosen = send("/csv/preview", text, column="imu.gyro 3").json()["positions"][0]
    assert chosen["mean_deg_h"] == pytest.approx(np.mean(axes[:, 2]) / RAD_S, rel=1e-12)
    assert send("/csv", text, column="imu.gyro 3", position=1).status_code == 200
    _, values, times = stored()
    np.testing.assert_allclose(values, axes[:, 2] / RAD_S, rtol=1e-14)
    np.testing.assert_allclose(times[:3], [0.0, 0.02, 0.04])


@pytest.mark.parametrize("columns", [1, 2, 3])
def test_numpy_arrays_in_the_apis_layouts_are_read(lab, columns):
    """``(n,)`` readings; ``(n, 2)`` time and reading; ``(n, 3)`` with the case
    temperature -- as the REST API takes a ``.npy``."""
    _, as_text, send = lab
    rates = omega(200)
    full = np.column_stack([0.1 * np.arange(200), rates, np.full(200, 25.5)])
    array = rates if columns == 1 else full[:, :columns]
    text = as_text(npy_file(array))["text"]
    assert send("/csv", text, position=2).status_code == 200
    take, values, times = stored()
    np.testing.assert_allclose(values, rates / RAD_S, rtol=1e-14)
    assert (times is not None) == (columns > 1)
    with read_session() as db:
        chunk = db.exec(select(SampleChunk)).one()
    assert (chunk.temperatures is not None) == (columns == 3)


def test_a_numpy_archive_of_named_vectors(lab):
    _, as_text, send = lab
    rates = omega(150)
    buffer = io.BytesIO()
    np.savez(buffer, time=0.2 * np.arange(150), rate=rates, note=np.array("bench 3"))
    data = buffer.getvalue()
    assert is_array_file(data)
    text = as_text(data)["text"]
    assert text.splitlines()[0] == "#time (s)\trate"
    assert send("/csv", text, position=4).status_code == 200
    _, values, times = stored()
    np.testing.assert_allclose(values, rates / RAD_S, rtol=1e-14)
    assert times[1] == pytest.approx(0.2)


def test_a_workbook_is_still_read_as_its_sheet(lab):
    """An ``.xlsx`` is a zip as a ``.npz`` is: told apart by its members."""
    from tests.test_workbook_readings import handout_rows, workbook

    _, as_text, _ = lab
    data = workbook(handout_rows())
    assert not is_array_file(data)
    book = as_text(data)
    assert book["sheet"] and book["text"].startswith("序号\t位置1")


def test_files_that_hold_no_record_are_refused_in_words(lab):
    client, as_text, _ = lab
    scalars = as_text(mat_file(omega=1.5e-5, Fs=10.0), status=400)
    assert "no vector of readings" in scalars["detail"]
    wide = as_text(npy_file(np.zeros((50, 5))), status=400)
    assert "(50, 5)" in wide["detail"]
    v73 = as_text(b"MATLAB 7.3 MAT-file, Platform: GLNXA64" + b"\x00" * 200, status=400)
    assert "-v7.3" in v73["detail"] or "7.3" in v73["detail"]
    client.cookies.set("gyrolab_lang", "zh-CN")
    damaged = as_text(b"\x93NUMPY\x01\x00garbage", status=400)
    assert "NumPy" in damaged["detail"] and "无法读取" in damaged["detail"]


def test_a_file_of_more_numbers_than_a_position_is_refused_before_it_is_written(lab):
    client, as_text, _ = lab
    rows = MAX_NUMBERS // 2 + 1
    data = mat_file(t=np.arange(rows) * 0.01, w=np.zeros(rows))
    assert len(data) < 5_000_000  # within the page's file size: the numbers are the limit
    refused = as_text(data, status=400)
    assert f"{2 * rows:,}".replace(",", "") in refused["detail"].replace(",", "")
    assert "this position's readings" in refused["detail"]
    client.cookies.set("gyrolab_lang", "zh-CN")
    assert "最多读取" in as_text(data, status=400)["detail"]
    with pytest.raises(UserError) as caught:
        array_file_text(data)
    assert caught.value.key == "arrays.too_many_numbers"


def test_names_that_would_split_the_header_are_written_as_one_cell():
    """A ``.npz``'s names are any text: a tab, a comma or a '#' in one would make two
    header cells or a comment."""
    buffer = io.BytesIO()
    np.savez(buffer, **{"gyro\tz,#1": omega(40)})
    header = array_file_text(buffer.getvalue()).splitlines()[0]
    assert header == "#gyro z 1"


def test_ten_readings_as_the_handout_takes_them_are_read(lab):
    """A position of the handout's ten readings is a vector of ten: read (the Allan
    analysis's record needs 16, a position does not); five are read as five, left to
    the lab's own flag of too few readings."""
    _, as_text, send = lab
    rates = omega(10)
    text = as_text(mat_file(omega=rates))["text"]
    assert send("/csv", text, position=1).status_code == 200
    _, values, _ = stored()
    np.testing.assert_allclose(values, rates / RAD_S, rtol=1e-14)
    few = send("/csv/preview", as_text(mat_file(omega=rates[:5]))["text"], position=2)
    assert few.status_code == 200 and few.json()["positions"][0]["n"] == 5


@pytest.mark.parametrize(
    "fault", [{"version": 85}, {"method": 9}, {"encrypted": True}], ids=["version", "m9", "lock"]
)
def test_zips_the_zip_module_cannot_read_are_refused_in_words(lab, fault):
    """A ``.npz`` or a workbook whose zip the module cannot open or read (a newer zip
    version, Deflate64, a password): was a 500 (NotImplementedError, RuntimeError)."""
    from tests.test_workbook_readings import handout_rows, workbook
    from tests.zip_faults import zip_patched

    _, as_text, _ = lab
    buffer = io.BytesIO()
    np.savez(buffer, rate=omega(40))
    for data in (buffer.getvalue(), workbook(handout_rows())):
        refused = as_text(zip_patched(data, **fault), status=400)
        assert "cannot be read" in refused["detail"] or "could not be read" in refused["detail"]


def test_vectors_named_for_their_positions_are_the_handouts_table(lab):
    """A student keeps the handout's table in MATLAB as ``p1`` … ``p4`` (one a reading
    longer): read as the four positions, and the heading is the handout's θ."""
    client, as_text, send = lab
    table = handout("handout_horizontal.csv")
    columns = [np.array(table[k]) for k in (1, 2, 3, 4)]
    data = mat_file(**{f"p{k}": column for k, column in enumerate(columns, start=1)}, Fs=1.0)
    text = as_text(data)["text"]
    assert text.splitlines()[0] == "position_1\tposition_2\tposition_3\tposition_4"
    longer = as_text(mat_file(p1=columns[0], p2=columns[1], p3=columns[2], p4=[*columns[3], -0.91]))
    preview = send("/csv/preview", longer["text"], unit="deg/h").json()
    assert [row["n"] for row in preview["positions"]] == [10, 10, 10, 11]
    saved = send("/csv", text, unit="deg/h")
    assert saved.status_code == 200 and saved.json()["saved"] == [1, 2, 3, 4]
    theta = client.get(f"{send.page}/results.json").json()["heading"]["theta_deg"]
    assert theta == pytest.approx(-10.753, abs=5e-4)  # the handout's θ


def test_position_names_that_clash_or_are_too_few_are_a_records_columns():
    """``p1`` and ``pos1`` name one position twice; two positions are no table: each is
    then offered as a record's column, as before."""
    clash = array_file_text(mat_file(p1=omega(20), pos1=omega(20), p2=omega(20), p3=omega(20)))
    assert clash.startswith("#")
    two = array_file_text(mat_file(p1=omega(20), p2=omega(20)))
    assert two.startswith("#p1\tp2")


def test_one_matrix_of_four_columns_and_nothing_else_is_the_handouts_table(lab):
    """``A = [10.74 2.88 -9.11 -0.96; …]`` saved alone (or as its transpose), and a
    ``.npy`` of four columns: the four positions, the handout's θ.  With a sample rate
    beside it the matrix is an IMU's record, offered axis by axis, as before."""
    client, as_text, send = lab
    table = handout("handout_horizontal.csv")
    matrix = np.column_stack([table[k] for k in (1, 2, 3, 4)])
    for data in (mat_file(A=matrix), mat_file(A=matrix.T), npy_file(matrix)):
        text = as_text(data)["text"]
        assert text.splitlines()[0] == "position_1\tposition_2\tposition_3\tposition_4"
    assert send("/csv", text, unit="deg/h").json()["saved"] == [1, 2, 3, 4]
    theta = client.get(f"{send.page}/results.json").json()["heading"]["theta_deg"]
    assert theta == pytest.approx(-10.753, abs=5e-4)
    assert as_text(mat_file(A=matrix, fs=10.0))["text"].startswith("#time (s)\tA 1")
    assert as_text(mat_file(gyro=np.column_stack([omega(50)] * 3)))["text"].startswith("#gyro 1")
