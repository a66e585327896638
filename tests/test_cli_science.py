"""``gyrolab solve`` / ``simulate`` / ``allan`` on the handout files and simulated data."""

from __future__ import annotations

import io
import json
import os
import subprocess
import sys

import pytest

from app.cli.main import main
from tests.factories import DATA, HEADING_KEYS, LATITUDE_KEYS


def run(capsys, *args: str, stdin: str | None = None):
    if stdin is not None:
        sys.stdin = io.StringIO(stdin)
    try:
        code = main(list(args))
    finally:
        sys.stdin = sys.__stdin__
    out, err = capsys.readouterr()
    return code, out, err


def test_solve_heading_json_on_the_handout(capsys):
    code, out, _ = run(capsys, "solve", "heading", str(DATA / "handout_horizontal.csv"), "--json")
    assert code == 0
    result = json.loads(out)
    assert list(result) == HEADING_KEYS
    assert result["theta_deg"] == pytest.approx(-10.753, abs=5e-4)
    assert result["rotate_direction"] == "counterclockwise"
    assert result["azimuth_error_deg"] is None


def test_solve_latitude_json_on_the_handout(capsys):
    code, out, _ = run(
        capsys,
        "solve",
        "latitude",
        str(DATA / "handout_vertical.csv"),
        "--latitude",
        "39.93",
        "--earth-rate",
        "15.04",
        "--json",
    )
    result = json.loads(out)
    assert code == 0 and list(result) == LATITUDE_KEYS
    assert result["latitude_deg"] == pytest.approx(40.727, abs=5e-4)
    assert result["latitude_error_percent"] == pytest.approx(2.00, abs=5e-3)
    assert result["earth_rate_error_percent"] == pytest.approx(0.62, abs=5e-3)


def test_solve_text_is_the_worked_calculation(capsys):
    code, out, _ = run(capsys, "solve", "heading", str(DATA / "handout_horizontal.csv"))
    assert code == 0
    assert "tan θ = (ω4 − ω2) / (ω1 − ω3)" in out and "-10.75°" in out
    turn = "From position 1, turn the table counter-clockwise by 10.75°: the axis then points north"
    assert turn in out
    code, out, _ = run(
        capsys,
        "solve",
        "latitude",
        str(DATA / "handout_vertical.csv"),
        "--latitude",
        "39.93",
        "--language",
        "zh-CN",
    )
    assert "由四个位置求纬度" in out and "η_φ" in out


def test_units_are_converted_at_the_boundary(capsys):
    text = (DATA / "handout_horizontal.csv").read_text().splitlines()
    header, rows = text[0], text[1:]
    scaled = [header] + [
        ",".join([r.split(",")[0]] + [str(float(v) / 3600) for v in r.split(",")[1:]]) for r in rows
    ]
    code, out, _ = run(
        capsys, "solve", "heading", "-", "--unit", "deg/s", "--json", stdin="\n".join(scaled)
    )
    assert code == 0
    result = json.loads(out)
    assert result["theta_deg"] == pytest.approx(-10.753, abs=5e-4)
    assert result["position_means_deg_h"][0] == pytest.approx(10.706)


def test_long_layout_uses_the_given_angles(capsys):
    rows = ["position,angle_deg,value"]
    for position, angle, value in [
        (1, 0, 10.706),
        (2, -90, 2.793),
        (3, -180, -8.951),
        (4, -270, -0.94),
    ]:
        rows += [f"{position},{angle},{value}"] * 3
    code, out, _ = run(
        capsys, "solve", "heading", "-", "--rotation", "cw", "--json", stdin="\n".join(rows)
    )
    assert code == 0 and json.loads(out)["azimuth_deg"] == pytest.approx(10.753, abs=1e-3)


def test_a_long_file_without_a_position_is_solved_at_its_positions_angles(capsys):
    """Positions 1, 2 and 4 named "P1, P2, P4" are at 0°, -90° and -270° (counter-
    clockwise), not at three positions' angles; the same heading as with all four."""
    means = {1: 10.706, 2: 2.793, 3: -8.951, 4: -0.94}  # the handout's means, heading 10.75°

    def solved(kept) -> float:
        rows = ["位置,读数"] + [f"P{k},{means[k]}" for k in kept for _ in range(3)]
        code, out, _ = run(capsys, "solve", "heading", "-", "--json", stdin="\n".join(rows))
        assert code == 0
        return json.loads(out)["azimuth_deg"]

    assert solved([2, 4, 1]) == pytest.approx(solved([1, 2, 3, 4]), abs=0.5)


@pytest.mark.parametrize("azimuth", [20.0, 110.0, 200.0, 290.0])
@pytest.mark.parametrize("rotation", ["ccw", "cw"])
def test_simulate_then_solve_every_quadrant(capsys, azimuth, rotation):
    code, csv_text, _ = run(
        capsys,
        "simulate",
        "heading",
        "--preset",
        "tactical-fog",
        "--latitude",
        "40",
        "--azimuth",
        str(azimuth),
        "--rotation",
        rotation,
        "--seconds-per-position",
        "60",
        "--seed",
        "3",
        "--indexing-sigma",
        "0",
    )
    assert code == 0 and csv_text.startswith("position,angle_deg,time_s,value")
    code, out, _ = run(
        capsys, "solve", "heading", "-", "--true-azimuth", str(azimuth), "--json", stdin=csv_text
    )
    result = json.loads(out)
    assert code == 0
    assert abs(result["azimuth_error_deg"]) < 4 * result["azimuth_sigma_deg"] + 0.05


def test_simulate_latitude_then_solve(capsys):
    code, csv_text, _ = run(
        capsys,
        "simulate",
        "latitude",
        "--preset",
        "tactical-fog",
        "--latitude",
        "39.93",
        "--seconds-per-position",
        "60",
        "--seed",
        "1",
    )
    code, out, _ = run(
        capsys, "solve", "latitude", "-", "--latitude", "39.93", "--json", stdin=csv_text
    )
    result = json.loads(out)
    assert code == 0 and abs(result["latitude_deg"] - 39.93) < 1.0


def test_simulate_static_and_allan(capsys, tmp_path):
    code, csv_text, _ = run(
        capsys,
        "simulate",
        "static",
        "--preset",
        "tactical-fog",
        "--latitude",
        "40",
        "--seconds",
        "600",
    )
    path = tmp_path / "static.csv"
    path.write_text(csv_text)
    code, out, _ = run(capsys, "allan", str(path), "--rate", "10", "--json")
    result = json.loads(out)
    assert code == 0
    assert result["arw_deg_rt_h"] == pytest.approx(0.012, rel=0.1)
    assert result["terms"]["arw"]["resolved"] and result["dwell"]["limit"] == "record"
    code, out, _ = run(capsys, "allan", str(path), "--rate", "10")
    assert "angle random walk N" in out and "0.01" in out and "best dwell" in out
    code, out, _ = run(capsys, "allan", str(path), "--language", "zh-CN")  # rate from times
    assert code == 0 and "角度随机游走 N" in out
    single = tmp_path / "single.txt"
    single.write_text("\n".join(csv_text.splitlines()[1:][i].split(",")[-1] for i in range(500)))
    assert run(capsys, "allan", str(single), "--rate", "10")[0] == 0


@pytest.mark.parametrize(
    ("args", "stdin", "message"),
    [
        (["solve", "heading", "/no/such/file.csv"], None, "no such file"),
        (["solve", "heading", "-"], "x,y\n1,2\n", "expected column names"),
        (["solve", "heading", "-"], "position_1,position_2\n1,2\n", "At least 3 different angles"),
        (["solve", "heading", "-"], "position_1,position_2,position_3\n1,abc,3\n", "not a number"),
        (["solve", "heading", "-"], "position_1,position_2,position_3\n1,nan,3\n", "not a number"),
        (["solve", "heading", "-"], "position_1,position_2\n1,1_000\n", "not a number"),
        (["solve", "heading", "-"], "position_1,position_2\n1,1e400\n", "out of range"),
        (["solve", "heading", "-", "--start-angle", "1e20"], "position_1\n1\n", "start angle"),
        (["solve", "heading", "-"], "position_1,position_2,position_3\n1,,3\n", "no readings"),
        (["solve", "heading", "-"], "", "no readings"),
        (["solve", "heading", "-", "--start-angle", "nan"], "position_1\n1\n", "finite"),
        (["allan", "-", "--rate", "10"], "1\n2\n", "at least 16"),
        (["simulate", "heading", "--latitude", "95"], None, "between -90 and 90"),
        # each of these was a traceback, NaN readings, a run out of memory, or taken
        (["simulate", "heading", "--latitude", "40", "--settle", "nan"], None, "finite"),
        (["simulate", "heading", "--latitude", "40", "--seed", "-1"], None, "--seed must be"),
        (["simulate", "heading", "--latitude", "40", "--earth-rate", "nan"], None, "finite"),
        (["simulate", "heading", "--latitude", "40", "--earth-rate", "-1"], None, "above 0"),
        (["simulate", "heading", "--latitude", "40", "--settle", "1e9"], None, "between 0 and"),
        (["simulate", "heading", "--latitude", "40", "--settle", "-1"], None, "between 0 and"),
        (["simulate", "heading", "--latitude", "40", "--rate", "-3"], None, "--rate must be above"),
        (["simulate", "heading", "--latitude", "40", "--positions", "10000"], None, "and 360"),
        (["simulate", "heading", "--latitude", "40", "--indexing-sigma", "-1"], None, "between"),
        (["simulate", "heading", "--latitude", "40", "--pitch", "100"], None, "between -90"),
        (["simulate", "static", "--latitude", "40", "--seconds", "1e9"], None, "shorter than"),
        (["simulate", "static", "--latitude", "40", "--seconds", "-5"], None, "above 0"),
    ],
)
def test_bad_input_exits_2_with_one_line(capsys, args, stdin, message):
    code, out, err = run(capsys, *args, stdin=stdin)
    assert code == 2
    assert message in err and len(err.strip().splitlines()) == 1
    assert "Traceback" not in err


@pytest.mark.parametrize(
    ("args", "english", "chinese"),
    [
        (
            ["solve", "heading", "/no/such.csv"],
            "no such file: /no/such.csv",
            "没有这个文件：/no/such.csv",
        ),
        (["allan", "/"], "/ is a folder, not a file", "/ 是文件夹，不是文件"),
        (
            ["solve", "heading", str(DATA / "handout_horizontal.csv"), "--latitude", "95"],
            "--latitude must be between -90 and 90 degrees",
            "--latitude 必须在 -90 到 90 度之间",
        ),
        (
            ["solve", "latitude", str(DATA / "handout_vertical.csv"), "--earth-rate", "1e300"],
            "--earth-rate must be above 0 and below 1000 °/h",
            "--earth-rate 必须大于 0 且小于 1000 °/h",
        ),
        (
            ["solve", "heading", "-", "--step", "inf"],
            "--step must be a finite number",
            "--step 必须是有限的数",
        ),  # fmt: skip
        (
            ["simulate"],
            "name what to simulate: heading, latitude or static",
            "请指定要模拟的内容：heading、latitude 或 static",
        ),  # fmt: skip
        (["simulate", "heading"], "--latitude is required", "需要 --latitude"),
        (
            ["errors"],
            "name a scenario (--scenario NAME) or --list",
            "请指定一个场景（--scenario 名称），或用 --list 列出场景",
        ),  # fmt: skip
    ],
)
def test_the_commands_own_messages_in_both_languages(capsys, monkeypatch, args, english, chinese):
    """The science commands' own refusals, like the core's, in the language asked for
    (``--language``, else the one ``LANG`` names); a true latitude beyond ±90° or an Earth
    rate outside (0, 1000) °/h is refused as the lab's pages and the API refuse it (it
    gave a percent error against latitude 95°)."""
    name = args[0]
    assert run(capsys, *args)[2] == f"gyrolab {name}: {english}\n"
    assert run(capsys, *args, "--language", "zh-CN")[2] == f"gyrolab {name}: {chinese}\n"
    monkeypatch.setenv("LANG", "zh_CN.UTF-8")
    code, _, err = run(capsys, *args)
    assert code == 2 and err == f"gyrolab {name}: {chinese}\n"
    assert run(capsys, *args, "--language", "en")[2] == f"gyrolab {name}: {english}\n"


def test_the_error_scenarios_report_in_chinese(capsys):
    code, out, _ = run(capsys, "errors", "--scenario", "indexing-level", "--language", "zh-CN")
    assert code == 0 and "方法 seeker（蒙特卡罗：每个方位" in out and "一阶公式 °" in out
    assert "论文：转位误差" in out.splitlines()[0]
    code, out, _ = run(capsys, "errors", "--scenario", "indexing-level", "--json")
    assert json.loads(out)["title"].startswith("Paper: indexing error")


def test_real_process_prints_no_traceback(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("position_1,position_2,position_3,position_4\n1,2,3,oops\n")
    process = subprocess.run(
        [sys.executable, "-m", "app.cli.main", "solve", "heading", str(bad)],
        capture_output=True,
        text=True,
    )
    assert process.returncode == 2
    assert process.stderr.strip() == (
        "gyrolab solve: Line 2, column position_4: 'oops' is not a number."
    )


def test_solve_with_a_gyro_preset_uses_its_noise_model(capsys):
    code, simulated, _ = run(
        capsys,
        "simulate", "heading", "--preset", "teaching-fog", "--latitude", "40",
        "--azimuth", "200", "--seconds-per-position", "300", "--seed", "3",
    )  # fmt: skip
    assert code == 0
    code, white, _ = run(capsys, "solve", "heading", "-", "--json", stdin=simulated)
    code, known, _ = run(
        capsys, "solve", "heading", "-", "--json", "--gyro-preset", "teaching-fog",
        stdin=simulated,
    )  # fmt: skip
    white, known = json.loads(white), json.loads(known)
    assert white["uncertainty_model"] == "white" and known["uncertainty_model"] == "allan"
    assert known["azimuth_deg"] == white["azimuth_deg"]  # the same fit, an honest σ
    assert known["azimuth_sigma_deg"] > 1.1 * white["azimuth_sigma_deg"]  # the slow bias


def test_simulate_lists_every_preset(capsys):
    from app.core.presets import PRESETS

    code, out, _ = run(capsys, "simulate", "--list-presets", "--json")
    assert code == 0
    rows = {row["name"]: row for row in json.loads(out)}
    assert set(rows) == set(PRESETS)
    assert rows["tactical-fog"]["arw_deg_rt_h"] == PRESETS["tactical-fog"].arw_deg_rt_h
    code, out, _ = run(capsys, "simulate", "--list-presets")
    assert code == 0 and "bias_instability_deg_h" in out and "source:" in out
    code, _, err = run(capsys, "simulate", "heading")
    assert code == 2 and "--latitude is required" in err


def test_a_cold_gyro_shows_its_warm_up_in_the_temperature_column(capsys):
    """The simulated case warms by ΔT(1 − e^(−t/τ)); solving a cold record warns that the
    bias drifted with it, and the heading error is larger than after warm-up."""
    common = ["simulate", "heading", "--preset", "teaching-fog", "--latitude", "40",
              "--azimuth", "135", "--seconds-per-position", "100", "--temperature",
              "--seed", "4"]  # fmt: skip
    errors = {}
    for warm_up in ("0", "3600"):
        code, csv_text, _ = run(capsys, *common, "--warm-up", warm_up)
        assert code == 0 and csv_text.splitlines()[0].endswith(",temperature_c")
        code, out, _ = run(
            capsys, "solve", "heading", "-", "--json", "--true-azimuth", "135", stdin=csv_text
        )
        result = json.loads(out)
        errors[warm_up] = abs(result["azimuth_error_deg"])
        temperature = result["temperature_c"]
        assert len(temperature["mean_by_position"]) == 4
        if warm_up == "0":
            first = float(csv_text.splitlines()[1].split(",")[-1])
            assert first == pytest.approx(20.0)
            assert temperature["change"] > 4.0 and "warming up" in temperature["note"]
        else:
            assert temperature["change"] < 0.1 and "steady" in temperature["note"]
    assert errors["0"] > 3 * errors["3600"]
    code, text, _ = run(capsys, "solve", "heading", "-", "--language", "zh-CN", stdin=csv_text)
    assert "温度稳定" in text


@pytest.mark.parametrize(
    ("encoding", "bom"),
    [
        ("utf-16", ""),  # utf-16 writes its own mark
        ("utf-16-be", "\ufeff"),
        ("gb18030", ""),
        ("utf-16-le", ""),  # a Windows program's "Unicode" without its mark
        ("utf-16-be", ""),
    ],
)
def test_solve_and_allan_read_the_encodings_spreadsheets_save(capsys, tmp_path, encoding, bom):
    """Excel's "Unicode text" (UTF-16 with its byte-order mark, tabs) and a Chinese-locale
    Excel's CSV (GB18030): solve said "not UTF-8 text", allan "not text"; UTF-16 without
    its mark was "not text" to both."""
    import numpy as np

    table = (DATA / "handout_horizontal.csv").read_text(encoding="utf-8-sig")
    path = tmp_path / "table.txt"
    path.write_bytes((bom + table.replace(",", "\t")).encode(encoding))
    code, out, _ = run(capsys, "solve", "heading", str(path), "--json")
    _, plain, _ = run(capsys, "solve", "heading", str(DATA / "handout_horizontal.csv"), "--json")
    assert code == 0 and json.loads(out)["azimuth_deg"] == json.loads(plain)["azimuth_deg"]
    rates = np.random.default_rng(5).normal(10.0, 0.5, 7_000)
    record = "时间,角速度\r\n" + "".join(f"{0.1 * k:.1f},{r:.4f}\r\n" for k, r in enumerate(rates))
    path = tmp_path / "record.csv"
    path.write_bytes((bom + record).encode(encoding))
    code, out, err = run(capsys, "allan", str(path), "--json")
    assert code == 0, err
    assert json.loads(out)["rate_hz"] == pytest.approx(10.0)


def test_allan_refuses_bytes_that_are_no_text(capsys, tmp_path):
    path = tmp_path / "record.bin"
    path.write_bytes(bytes(range(256)) * 8)
    code, _, err = run(capsys, "allan", str(path))
    assert code != 0 and "not text" in err


def test_a_reader_that_stops_early_gets_no_traceback():
    # ``gyrolab simulate --list-presets | head -1``: the reader has gone before the writing
    # ends (here, before it starts: the pipe's reading end is closed, so that every write
    # meets a broken pipe, deterministically)
    read_end, write_end = os.pipe()
    os.close(read_end)
    try:
        done = subprocess.run(
            [sys.executable, "-m", "app.cli.main", "simulate", "--list-presets"],
            stdout=write_end,
            stderr=subprocess.PIPE,
            timeout=120,
        )
    finally:
        os.close(write_end)
    assert done.returncode == 0 and done.stderr == b"", done.stderr


def test_solve_refuses_one_positions_record_and_reads_a_matlab_table(capsys, tmp_path):
    """A logger's or an IMU's record, LabVIEW's .lvm, a MATLAB vector: one position, whose
    time and axis columns ``solve`` read as four positions (an IMU's record "solved" to a
    heading; an .lvm was "a second table") -- now refused, pointing to the lab page and
    ``allan``; a MATLAB file of ``p1`` … ``p4`` is the handout's table."""
    import numpy as np
    import scipy.io

    from tests.factories import handout
    from tests.test_labview_lvm import lvm
    from tests.test_position_record_files import axes_file, imu_file

    table = handout("handout_horizontal.csv")
    rates = np.array(table[1])
    records = {
        "imu.csv": imu_file([float(v) for v in rates]).encode(),
        "fog.lvm": lvm(np.tile(rates, 3)).encode(),
        # its header not behind '#': it was solved as four positions, the times position 1
        "export.csv": axes_file("Time (s),Gyro X,Gyro Y,Gyro Z", rates).encode(),
    }
    for name, data in records.items():
        (tmp_path / name).write_bytes(data)
    scipy.io.savemat(tmp_path / "imu.mat", {"gyro": np.column_stack([rates] * 3), "Fs": 10.0})
    for name in (*records, "imu.mat"):
        code, out, err = run(capsys, "solve", "heading", str(tmp_path / name))
        assert code == 2 and out == "", name
        assert "is one position's record" in err and "gyrolab allan" in err, (name, err)
    code, _, err = run(capsys, "solve", "heading", str(tmp_path / "fog.lvm"), "--language", "zh-CN")
    assert code == 2 and "是一个位置的记录" in err
    scipy.io.savemat(tmp_path / "table.mat", {f"p{k}": table[k] for k in (1, 2, 3, 4)})
    code, out, _ = run(capsys, "solve", "heading", str(tmp_path / "table.mat"), "--json")
    assert code == 0 and json.loads(out)["theta_deg"] == pytest.approx(-10.753, abs=5e-4)
