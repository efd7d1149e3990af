"""The `gearsim` command: JSON shapes and exit codes of compare, diagnose, fit
and report (docs/measurement-format.md section 4), and bad input: exit 2 with
one line naming file / line / column / key, no traceback, nothing written."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys

import pytest
from analysis_helpers import CONTRACT_EFFECTS

import gearsim


def run(*args: str, cwd=None) -> subprocess.CompletedProcess:
    env = dict(os.environ)
    env.pop("GEARSIM_DEBUG", None)
    return subprocess.run(
        [sys.executable, "-m", "gearsim.cli", *map(str, args)],
        capture_output=True,
        text=True,
        cwd=cwd,
        env=env,
        timeout=300,
    )


def one_json(p: subprocess.CompletedProcess) -> dict:
    assert p.returncode == 0, p.stderr
    lines = [ln for ln in p.stdout.splitlines() if ln.strip()]
    assert len(lines) == 1, p.stdout
    return json.loads(lines[0])


def finite(x) -> bool:
    return isinstance(x, float) and math.isfinite(x)


def test_compare_json(gear_csv):
    csv, model = gear_csv
    out = one_json(run("compare", csv, "--model", model, "--json"))
    assert set(out["outputs"]) == {"base_torque", "follower_speed"}
    for m in out["outputs"].values():
        assert all(finite(m[k]) for k in ("nrmse", "rmse", "max_abs"))
    assert out["nrmse"] == pytest.approx(sum(m["nrmse"] for m in out["outputs"].values()) / 2)
    assert {r["regime"] for r in out["regimes"]} >= {
        "direction_reversal",
        "low_speed",
        "overrunning",
    }


def test_compare_text(gear_csv):
    csv, model = gear_csv
    p = run("compare", csv, "--model", model, "--quiet")
    assert p.returncode == 0, p.stderr
    assert "base_torque" in p.stdout and "overall" in p.stdout
    assert p.stderr == ""


def test_diagnose_json(gear_csv):
    csv, model = gear_csv
    p = run("diagnose", csv, "--model", model, "--json")
    out = one_json(p)
    assert finite(out["baseline_nrmse"])
    cands = out["candidates"]
    assert cands and cands[0]["effect"] == "coulomb_friction"
    for c in cands:
        assert c["effect"] in CONTRACT_EFFECTS
        assert finite(c["nrmse_after"]) and isinstance(c["parameters"], dict)
        assert finite(c["score"]) and c["method"] in ("fit", "screening")
        assert finite(c["validation_nrmse_after"]) and isinstance(c["helps"], bool)
    assert len({c["effect"] for c in cands}) == len(cands)
    # fitted candidates first, each group by score unless a simpler one is within the noise
    methods = [c["method"] for c in cands]
    assert methods == sorted(methods, key=lambda m: m != "fit")
    val = out["validation"]
    assert val["enabled"] is True and val["fraction"] == pytest.approx(0.3)
    assert val["held_out_blocks"] == [3, 6, 9] and finite(val["baseline_nrmse"])
    assert cands[0]["helps"] and out["conclusion"].startswith("add coulomb_friction")
    assert all({"kind", "text"} <= set(w) for w in out["warnings"])
    # progress went to stderr, not into the JSON
    assert "screen" in p.stderr


def test_diagnose_text_shows_score_method_and_conclusion(gear_csv):
    csv, model = gear_csv
    p = run("diagnose", csv, "--model", model, "--quiet", "--no-validation")
    assert p.returncode == 0, p.stderr
    head = next(ln for ln in p.stdout.splitlines() if ln.startswith("rank"))
    assert "score" in head and "method" in head and "validation" in head
    assert "validation off" in p.stdout
    assert p.stdout.rstrip().splitlines()[-1].startswith("add coulomb_friction")


def test_validation_switch_and_fraction(gear_csv):
    csv, model = gear_csv
    on = one_json(
        run("fit", csv, "--model", model, "--add", "coulomb_friction", "--json", "--quiet")
    )
    off = one_json(
        run(
            "fit",
            csv,
            "--model",
            model,
            "--add",
            "coulomb_friction",
            "--json",
            "--quiet",
            "--no-validation",
        )
    )
    assert on["validation"]["enabled"] and not off["validation"]["enabled"]
    # off: judged on the whole record
    assert off["validation"]["nrmse_after"] == pytest.approx(off["nrmse_after"])
    assert on["validation"]["nrmse_after"] < 0.5 * on["validation"]["nrmse_before"]
    half = one_json(
        run(
            "diagnose",
            csv,
            "--model",
            model,
            "--json",
            "--quiet",
            "--no-fit",
            "--validation-fraction",
            "0.5",
        )
    )
    assert half["validation"]["held_out_blocks"] == [1, 3, 5, 7, 9]
    _bad(run("diagnose", csv, "--model", model, "--validation-fraction", "0.9"), "fraction")


def test_diagnose_skips_effects_the_model_has(tmp_path, gear_csv):
    csv, _ = gear_csv
    model = tmp_path / "m.toml"
    gearsim.Model(
        "simple_gear",
        {"teeth_ratio": 3.0, "base_radius": 0.05},
        {"follower_inertia": 0.05, "load_coulomb_friction": 1.0},
    ).save(model)
    out = one_json(run("diagnose", csv, "--model", model, "--json", "--no-fit"))
    assert "coulomb_friction" not in {c["effect"] for c in out["candidates"]}


def test_fit_json_and_out(tmp_path, gear_csv):
    csv, model = gear_csv
    new = tmp_path / "new.toml"
    out = one_json(
        run("fit", csv, "--model", model, "--add", "coulomb_friction", "--out", new, "--json")
    )
    assert out["effect"] == "coulomb_friction"
    assert out["nrmse_after"] < 0.5 * out["nrmse_before"]
    assert out["parameters"]["load_coulomb_friction"] == pytest.approx(1.5, rel=0.1)
    assert "follower_inertia" in out["coestimated"]
    fitted = gearsim.Model.load(new)
    assert fitted.resolved_rig_params["load_coulomb_friction"] == pytest.approx(
        out["parameters"]["load_coulomb_friction"]
    )
    # the written model is ready for the next round: compare it
    again = one_json(run("compare", csv, "--model", new, "--json"))
    assert again["nrmse"] == pytest.approx(out["nrmse_after"], rel=1e-6)
    # and coulomb friction is no longer a candidate
    p = run("fit", csv, "--model", new, "--add", "coulomb_friction")
    assert p.returncode == 2 and "already" in p.stderr


def test_fit_sensor_delay_writes_the_analysis_table(tmp_path):
    # the torque column logged 5 samples late: fit writes [analysis]
    # torque_delay, and compare applies it when it reads the new model
    import tomllib

    from analysis_helpers import base_model, measurement

    from gearsim.analysis import Measurement, write_measurement

    meas = measurement("simple_gear", ("coulomb_friction",), samples=4000)
    spec = meas.spec
    cols = {c: meas[c] for c in (spec.speed_input, spec.load_input, spec.speed_output)}
    torque = meas[spec.torque_output]
    cols[spec.torque_output] = [torque[0]] * 5 + list(torque[:-5])
    csv = tmp_path / "late.csv"
    write_measurement(csv, Measurement.from_arrays("simple_gear", meas.time, path="late", **cols))
    model = tmp_path / "model.toml"
    base_model("simple_gear").replace(rig_params={"load_coulomb_friction": 1.5}).save(model)
    new = tmp_path / "new.toml"
    out = one_json(
        run("fit", csv, "--model", model, "--add", "sensor_delay", "--out", new, "--json")
    )
    assert out["parameters"]["torque_delay"] == pytest.approx(5e-3, abs=2.5e-4)
    table = tomllib.loads(new.read_text())["analysis"]
    assert table["torque_delay"] == pytest.approx(out["parameters"]["torque_delay"])
    again = one_json(run("compare", csv, "--model", new, "--json"))
    assert again["nrmse"] == pytest.approx(out["nrmse_after"], rel=1e-6)
    p = run("fit", csv, "--model", new, "--add", "sensor_delay")
    assert p.returncode == 2 and "already" in p.stderr


def test_bad_analysis_key(tmp_path, gear_csv):
    csv, _ = gear_csv
    model = tmp_path / "bad.toml"
    model.write_text(
        '[rig]\nblock = "simple_gear"\n[block]\nteeth_ratio = 3.0\n'
        '[analysis]\ntorque_delay = "3 parsecs"\n'
    )
    _bad(run("compare", csv, "--model", model), "bad.toml", "torque_delay")


def test_report(tmp_path, gear_csv):
    csv, model = gear_csv
    out_dir = tmp_path / "rep"
    out = one_json(
        run("report", csv, "--model", model, "--out", out_dir, "--rounds", "1", "--json")
    )
    html = (out_dir / "report.html").read_text()
    assert html.count("data:image/png;base64,") >= 5
    for name in ("overlay", "residual", "residual_vs", "regimes", "error_fall", "signatures"):
        assert (out_dir / f"{name}.png").stat().st_size > 1000
    assert [r["effect"] for r in out["rounds"]] == [None, "coulomb_friction"]
    # Coulomb friction's look-alike with a signature plot is among the first
    # candidates: its friction-against-speed plot is on the page
    assert "Signatures of the effects diagnosed" in html
    r0, r1 = out["rounds"]
    assert r1["validation_nrmse"] < 0.5 * r0["validation_nrmse"]
    assert "validation" in html and "score" in html and "fails" in html


def test_report_runs_rounds_by_default(tmp_path, gear_csv):
    csv, model = gear_csv
    out = one_json(run("report", csv, "--model", model, "--out", tmp_path / "r", "--json"))
    # rounds until nothing helps (at most 3): coulomb friction first, then the stop line
    assert out["rounds"][1]["effect"] == "coulomb_friction"
    assert len(out["rounds"]) <= 4
    if len(out["rounds"]) < 4:
        assert out["conclusion"].startswith("nothing left that helps")


# ---------------------------------------------------------------- bad input


def _bad(p: subprocess.CompletedProcess, *needles: str) -> None:
    assert p.returncode == 2, (p.returncode, p.stderr)
    err = p.stderr.strip().splitlines()
    assert len(err) == 1, p.stderr
    assert "Traceback" not in p.stderr
    for n in needles:
        assert n in err[0], err[0]
    assert p.stdout == ""


def _csv(tmp_path, text: str):
    f = tmp_path / "bad.csv"
    f.write_text(text)
    return f


def _rows(n=30, **override):
    head = "time,base_speed,load_torque,base_torque,follower_speed\n"
    rows = [f"{i * 0.001:.3f},{1 + i % 3},0.5,0.2,{-(1 + i % 3) / 3:.4f}" for i in range(n)]
    for line, text in override.items():
        rows[int(line[1:]) - 2] = text
    return head + "\n".join(rows) + "\n"


@pytest.mark.parametrize("command", ["compare", "diagnose", "fit"])
def test_missing_data_file(tmp_path, gear_csv, command):
    _, model = gear_csv
    extra = ["--add", "coulomb_friction"] if command == "fit" else []
    _bad(run(command, tmp_path / "nope.csv", "--model", model, *extra), "nope.csv", "no such file")


def test_missing_model_file(tmp_path, gear_csv):
    csv, _ = gear_csv
    _bad(run("compare", csv, "--model", tmp_path / "nope.toml"), "nope.toml")


def test_missing_column(tmp_path, gear_csv):
    _, model = gear_csv
    f = _csv(tmp_path, _rows().replace("load_torque", "load"))
    _bad(
        run("compare", f, "--model", model), "bad.csv", "line 1", "'load_torque'", "missing column"
    )


def test_non_numeric_cell(tmp_path, gear_csv):
    _, model = gear_csv
    f = _csv(tmp_path, _rows(L7="0.005,1,abc,0.2,-0.3"))
    _bad(run("compare", f, "--model", model), "bad.csv", "line 7", "'load_torque'", "'abc'")


@pytest.mark.parametrize("value", ["nan", "inf", "-inf"])
def test_non_finite(tmp_path, gear_csv, value):
    _, model = gear_csv
    f = _csv(tmp_path, _rows(L9=f"0.007,1,0.5,{value},-0.3"))
    _bad(run("compare", f, "--model", model), "line 9", "'base_torque'", "not finite")


def test_time_not_increasing(tmp_path, gear_csv):
    _, model = gear_csv
    f = _csv(tmp_path, _rows(L12="0.009,1,0.5,0.2,-0.3"))
    _bad(run("compare", f, "--model", model), "line 12", "'time'", "not after")


def test_non_uniform_sampling(tmp_path, gear_csv):
    _, model = gear_csv
    text = _rows(40)
    lines = text.splitlines()
    del lines[20]  # a lost sample
    f = _csv(tmp_path, "\n".join(lines) + "\n")
    _bad(run("compare", f, "--model", model), "line 21", "not uniform", "--resample")
    p = run("compare", f, "--model", model, "--resample", "--json", "--quiet")
    assert p.returncode == 0, p.stderr


def test_short_row(tmp_path, gear_csv):
    _, model = gear_csv
    f = _csv(tmp_path, _rows(L5="0.003,1,0.5"))
    _bad(run("compare", f, "--model", model), "line 5", "'base_torque'")


def test_extra_columns_ignored(tmp_path, gear_csv):
    _, model = gear_csv
    text = _rows(40).splitlines()
    text = [text[0] + ",comment"] + [ln + ",free text" for ln in text[1:]]
    f = _csv(tmp_path, "\n".join(text) + "\n")
    assert run("compare", f, "--model", model, "--json", "--quiet").returncode == 0


def test_unknown_effect(tmp_path, gear_csv):
    csv, model = gear_csv
    out = tmp_path / "new.toml"
    _bad(
        run("fit", csv, "--model", model, "--add", "magic_friction", "--out", out), "magic_friction"
    )
    assert not out.exists()


def test_effect_not_for_this_rig(tmp_path):
    from analysis_helpers import base_model, measurement

    from gearsim.analysis import write_measurement

    csv = tmp_path / "rack.csv"
    write_measurement(csv, measurement("rack_pinion", ("load_offset",), samples=2000))
    model = tmp_path / "rack.toml"
    base_model("rack_pinion").save(model)
    _bad(
        run("fit", csv, "--model", model, "--add", "load_dependent_efficiency"),
        "load_dependent_efficiency",
        "rack_pinion",
    )


def test_invalid_parameter_in_model(tmp_path, gear_csv):
    csv, _ = gear_csv
    model = tmp_path / "bad.toml"
    model.write_text(
        '[rig]\nblock = "simple_gear"\nfollower_inertia = -1.0\n[block]\nteeth_ratio = 3.0\n'
    )
    out = tmp_path / "new.toml"
    _bad(
        run("fit", csv, "--model", model, "--add", "load_offset", "--out", out), "follower_inertia"
    )
    assert not out.exists()


def test_unknown_model_key(tmp_path, gear_csv):
    csv, _ = gear_csv
    model = tmp_path / "bad.toml"
    model.write_text('[rig]\nblock = "simple_gear"\n[block]\nteeth_ration = 3.0\n')
    _bad(run("compare", csv, "--model", model), "teeth_ration")


def test_gear_model_on_rack_data(tmp_path):
    from analysis_helpers import measurement

    from gearsim.analysis import write_measurement

    csv = tmp_path / "rack.csv"
    write_measurement(csv, measurement("rack_pinion", ("load_offset",), samples=2000))
    model = tmp_path / "gear.toml"
    gearsim.Model("simple_gear").save(model)
    _bad(run("compare", csv, "--model", model), "rack.csv", "'base_speed'", "missing column")


def test_bad_input_writes_nothing(tmp_path, gear_csv):
    _, model = gear_csv
    out_dir = tmp_path / "rep"
    f = _csv(tmp_path, _rows(L9="0.007,1,0.5,nan,-0.3"))
    _bad(run("report", f, "--model", model, "--out", out_dir))
    assert not out_dir.exists()
    out = tmp_path / "new.toml"
    _bad(run("fit", f, "--model", model, "--add", "load_offset", "--out", out))
    assert not out.exists()


def test_usage_error_is_one_line():
    p = run("fit")
    assert p.returncode == 2
    assert len(p.stderr.strip().splitlines()) == 1 and "Traceback" not in p.stderr


def test_column_mapping(tmp_path, gear_csv):
    csv, model = gear_csv
    text = csv.read_text().replace("base_speed", "omega_rpm", 1)
    f = tmp_path / "mapped.csv"
    f.write_text(text)
    ref = one_json(run("compare", csv, "--model", model, "--json", "--quiet"))
    p = one_json(
        run("compare", f, "--model", model, "--json", "--quiet", "--column", "base_speed=omega_rpm")
    )
    assert p["nrmse"] == pytest.approx(ref["nrmse"])
    _bad(run("compare", f, "--model", model), "'base_speed'", "missing column")


def test_help_lists_the_commands():
    p = run("--help")
    assert p.returncode == 0
    for cmd in ("compare", "diagnose", "fit", "report"):
        assert cmd in p.stdout
