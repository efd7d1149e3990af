"""Fleet-level input: what makes the fleet unreadable ends the command with
exit status 2, one line naming the file, row and column, before any work
and without writing anything; the population's numbers on hand-made data."""

from __future__ import annotations

import math
import shutil
import subprocess
import sys

import numpy as np
import pytest

from gearsim.cli import main
from gearsim.fleet import Sample, find_units, population
from gearsim.fleet.units import unit_id_of


@pytest.fixture
def small(line, tmp_path):
    """Four logs of the line in a directory, their manifest and the model."""
    specs, manifest, model = line
    logs = tmp_path / "logs"
    logs.mkdir()
    for s in specs[:4]:
        shutil.copy(manifest.parent / f"{s.unit}.csv", logs / f"{s.unit}.csv")
    man = logs / "manifest.csv"
    man.write_text(
        "unit,path,line,station,timestamp\n"
        + "".join(
            f"{s.unit},{s.unit}.csv,L1,S1,2026-11-02T0{i}:00:00Z\n" for i, s in enumerate(specs[:4])
        )
    )
    return logs, man, model


def _cli(argv, capsys):
    status = main(argv)
    cap = capsys.readouterr()
    return status, cap.out, cap.err


def _one_line(status, out, err):
    assert status == 2, err
    assert out == ""
    assert len(err.strip().splitlines()) == 1, err
    return err.strip()


def test_units_from_a_directory_a_glob_and_a_manifest(small):
    logs, man, _ = small
    by_dir = find_units(str(logs))
    assert [u.unit for u in by_dir] == sorted(u.unit for u in by_dir)
    # every CSV of the folder is a log, the manifest too (give a glob to leave it out)
    assert [u.unit for u in by_dir] == [f"gx-000{i}" for i in range(4)] + ["manifest"]
    by_glob = find_units(str(logs / "gx-*.csv"))
    assert [u.unit for u in by_glob] == [f"gx-000{i}" for i in range(4)]
    by_man = find_units(manifest=str(man))
    assert [u.unit for u in by_man] == [f"gx-000{i}" for i in range(4)]
    assert by_man[2].timestamp.isoformat() == "2026-11-02T02:00:00+00:00"
    assert by_man[0].line == "L1" and by_man[0].station == "S1"
    assert unit_id_of("a/b/unit-7.csv.gz") == "unit-7"


@pytest.mark.parametrize(
    "text, expect",
    [
        ("unit,path\nA,a.csv\n,b.csv\n", "manifest.csv, line 3, column 'unit': empty"),
        ("unit,path\nA,a.csv\nA,b.csv\n", "line 3, column 'unit': 'A' already on line 2"),
        ("unit,file\nA,a.csv\n", "line 1: the manifest has no column 'path'"),
        (
            "unit,path,timestamp\nA,a.csv,yesterday\n",
            "line 2, column 'timestamp': timestamp 'yesterday'",
        ),
        (
            "unit,path,timestamp\nA,a.csv,2026-01-01T00:00Z\nB,b.csv,2026-01-01T00:00\n",
            "line 3, column 'timestamp': without a time zone, line 2 with",
        ),
        ("unit,path,line\nA,a.csv\n", "line 2: 2 cells, the header has 3"),
        ("unit,path\n", "lists no unit"),
        ("", "the manifest is empty"),
    ],
)
def test_bad_manifest_rows_exit_2_naming_row_and_column(tmp_path, capsys, text, expect, line):
    man = tmp_path / "manifest.csv"
    man.write_text(text)
    out = tmp_path / "out"
    status, o, e = _cli(
        [
            "fleet",
            "--manifest",
            str(man),
            "--model",
            str(line[2]),
            "--out",
            str(out),
            "--add",
            "coulomb_friction",
        ],
        capsys,
    )
    msg = _one_line(status, o, e)
    assert expect in msg, msg
    assert not out.exists()


def test_bad_fleet_inputs_exit_2(small, tmp_path, capsys):
    logs, man, model = small
    out = tmp_path / "out"
    cases = [
        ([str(tmp_path / "nowhere"), "--add", "coulomb_friction"], "no such directory or file"),
        ([str(tmp_path / "nowhere" / "*.csv"), "--add", "coulomb_friction"], "no file matches"),
        ([str(tmp_path), "--add", "coulomb_friction"], "no log in the directory"),
        ([str(logs)], "--add EFFECT"),
        ([str(logs), "--add", "no_such_effect"], "no_such_effect"),
        ([str(logs), "--add", "coulomb_friction,coulomb_friction"], "named twice"),
        ([str(logs), "--add", "coulomb_friction", "--manifest", str(man)], "one of them"),
        ([str(logs), "--add", "coulomb_friction", "--input-filter", "fast"], "--input-filter"),
        ([str(logs), "--add", "coulomb_friction", "--threshold", "-1"], "--threshold"),
        ([str(logs), "--add", "coulomb_friction", "--column", "base_speed"], "base_speed"),
    ]
    for argv, expect in cases:
        status, o, e = _cli(["fleet", *argv, "--model", str(model), "--out", str(out)], capsys)
        assert expect in _one_line(status, o, e), (argv, e)
        assert not out.exists(), argv
    bad_model = tmp_path / "bad.toml"
    bad_model.write_text("[rig]\nblock = 'simple_gear'\nfollower_inertia = -1\n")
    status, o, e = _cli(
        [
            "fleet",
            str(logs),
            "--add",
            "coulomb_friction",
            "--model",
            str(bad_model),
            "--out",
            str(out),
        ],
        capsys,
    )
    assert "bad.toml" in _one_line(status, o, e)


def test_no_output_goes_among_the_inputs(small, capsys):
    logs, man, model = small
    before = {p: p.read_bytes() for p in logs.iterdir()}
    for out in (logs, logs.parent):  # the logs' own folder, or one holding them
        status, o, e = _cli(
            [
                "fleet",
                str(logs),
                "--model",
                str(model),
                "--out",
                str(out),
                "--add",
                "coulomb_friction",
            ],
            capsys,
        )
        assert "holds an input" in _one_line(status, o, e)
    status, o, e = _cli(
        [
            "fleet",
            "--manifest",
            str(man),
            "--model",
            str(model),
            "--out",
            str(model.parent),
            "--add",
            "coulomb_friction",
        ],
        capsys,
    )
    assert "holds an input" in _one_line(status, o, e)
    assert {p: p.read_bytes() for p in logs.iterdir()} == before


def test_help_lists_the_command():
    out = subprocess.run(
        [sys.executable, "-m", "gearsim.cli", "fleet", "--help"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 0 and "--scheduler" in out.stdout and "--manifest" in out.stdout


# ------------------------------------------------------------------ population


def _samples(values: dict[str, list[float]], errors: list[float]) -> list[Sample]:
    n = len(errors)
    return [Sample(f"u{i}", {k: v[i] for k, v in values.items()}, errors[i]) for i in range(n)]


def test_robust_z_by_hand():
    # 12 units: a at 10 +- a few, one at 13; MAD by hand
    a = [10.0, 10.1, 9.9, 10.2, 9.8, 10.0, 10.1, 9.9, 10.0, 10.05, 9.95, 13.0]
    err = [0.05] * 11 + [0.05]
    pop = population(_samples({"a": a}, err))
    # sorted: 9.8 9.9 9.9 9.95 10 10 10 10.05 10.1 10.1 10.2 13 -> median 10.0
    # |dev|: .2 .1 .1 .05 0 0 0 .05 .1 .1 .2 3 -> sorted 0 0 0 .05 .05 .1 .1 .1 .1 .2 .2 3 -> MAD .1
    st = pop["parameters"]["a"]
    assert st["median"] == 10.0 and math.isclose(st["mad"], 0.1)
    assert math.isclose(st["sigma"], 0.14826)
    assert [o["unit"] for o in pop["outliers"]] == ["u11"]
    assert math.isclose(pop["outliers"][0]["z"], 3.0 / 0.14826)
    # the remaining error all equal: no spread (MAD 0 and mean deviation 0) -> never judged
    assert pop["remaining_error"]["sigma"] == 0.0


def test_remaining_error_counts_on_its_high_side_only():
    rng = np.random.default_rng(4)
    a = list(10 + 0.1 * rng.standard_normal(40))
    err = list(0.05 + 0.001 * rng.standard_normal(40))
    err[5], err[6] = 0.08, 0.02  # far above, far below
    pop = population(_samples({"a": a}, err))
    units = {o["unit"]: o["by"] for o in pop["outliers"]}
    assert units.get("u5") == "nrmse_after" and "u6" not in units


def test_mad_zero_falls_back_to_the_mean_deviation():
    a = [1.0] * 10 + [2.0, 5.0]  # more than half equal: MAD 0
    pop = population(_samples({"a": a}, [0.1 + 0.01 * i for i in range(12)]))
    st = pop["parameters"]["a"]
    assert st["mad"] == 0.0 and math.isclose(st["sigma"], 1.2533 * (1.0 + 4.0) / 12)
    assert [o["unit"] for o in pop["outliers"] if o["by"] == "a"] == ["u11"]


def test_too_few_units_give_no_population():
    pop = population(_samples({"a": [1.0] * 5}, [0.1] * 5))
    assert pop["outliers"] == [] and "fewer than" in pop["note"]


@pytest.mark.parametrize("seed", range(6))
def test_false_outliers_of_a_normal_population_are_rare_and_a_planted_one_is_found(seed):
    """Seeded random populations: the count of false outliers over three
    metrics of 2000 normal units stays near the tail probability of 3.5
    sigma (0.047 %), and a unit planted 8 sigma off is found by its metric."""
    rng = np.random.default_rng(seed)
    n = 2000
    vals = {
        k: list(rng.normal(c, s, n))
        for k, c, s in (("a", 1.5, 0.05), ("b", 0.8, 0.006), ("c", -3.0, 0.2))
    }
    err = list(np.abs(rng.normal(0.05, 0.001, n)))
    k = int(rng.integers(n))
    name = ["a", "b", "c"][seed % 3]
    sign = 1 if seed % 2 else -1
    scale = {"a": 0.05, "b": 0.006, "c": 0.2}[name]
    vals[name][k] += sign * 8 * scale
    pop = population(_samples(vals, err))
    found = {o["unit"]: o["by"] for o in pop["outliers"]}
    assert found.get(f"u{k}") == name
    false = len(found) - 1
    # expected 4 x 2000 x 4.65e-4 / 2 (one-sided error) ~ 3.3; far tail of a Poisson
    assert false <= 12, false


def test_drift_slope_of_a_trend_with_outliers():
    from datetime import UTC, datetime, timedelta

    rng = np.random.default_rng(9)
    n = 120
    t0 = datetime(2026, 1, 1, tzinfo=UTC)
    days = np.arange(n) / 24.0  # one an hour, 5 days
    a = 2.0 + 0.03 * days + 0.01 * rng.standard_normal(n)
    a[[10, 50, 90]] += 1.0  # outliers do not set the trend
    samples = [
        Sample(
            f"u{i}",
            {"a": float(a[i]), "b": float(rng.normal())},
            0.05 + 0.001 * rng.normal(),
            t0 + timedelta(days=float(days[i])),
        )
        for i in range(n)
    ]
    pop = population(samples)
    d = pop["drift"]["a"]
    assert d["drifting"] and math.isclose(d["slope_per_day"], 0.03, rel_tol=0.15)
    assert not pop["drift"]["b"]["drifting"]
