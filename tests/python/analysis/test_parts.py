"""Building blocks: metrics, zero-phase filter, measurement checks, regimes,
residual signatures, the effect table."""

from __future__ import annotations

import numpy as np
import pytest
from analysis_helpers import CONTRACT_EFFECTS, base_model, measurement

from gearsim.analysis import EFFECT_NAMES, Measurement, MeasurementError, compare, load_measurement
from gearsim.analysis.effects import applicable_effects, get_effect
from gearsim.analysis.errors import EffectError
from gearsim.analysis.metrics import nrmse, output_metrics
from gearsim.analysis.regimes import segment, sign_changes
from gearsim.analysis.signals import auto_cutoff, zero_phase_lowpass


def test_metrics():
    t = np.arange(100) * 0.01
    y = np.sin(t * 5)
    assert nrmse(y, y) == 0.0
    assert nrmse(y, np.full_like(y, y.mean())) == pytest.approx(1.0)
    e = np.zeros_like(y)
    e[37] = 2.0
    m = output_metrics(y, y - e, t)
    assert m.max_abs == pytest.approx(2.0) and m.t_max_abs == pytest.approx(t[37])
    assert m.fit_percent == pytest.approx(100 * (1 - m.nrmse))
    # NRMSE fit % as system identification defines it
    assert m.fit_percent == pytest.approx(
        100 * (1 - np.linalg.norm(e) / np.linalg.norm(y - y.mean()))
    )


def test_zero_phase_filter_has_no_delay():
    fs = 1000.0
    t = np.arange(5000) / fs
    x = np.sin(2 * np.pi * 2 * t)
    rng = np.random.default_rng(0)
    y = zero_phase_lowpass(x + 0.1 * rng.standard_normal(t.size), 30.0, fs)
    lag = np.argmax(np.correlate(y[500:-500], x[500:-500], "full")) - (t.size - 1001)
    assert lag == 0
    assert np.std(y - x) < 0.03
    # edges keep value and slope
    assert abs(y[0] - x[0]) < 0.05


def test_auto_cutoff_separates_noise():
    fs = 1000.0
    t = np.arange(20000) / fs
    clean = np.sin(2 * np.pi * 1.5 * t) + 0.3 * np.sin(2 * np.pi * 4 * t)
    noisy = clean + 0.01 * np.random.default_rng(1).standard_normal(t.size)
    fc = auto_cutoff(noisy, fs)
    assert 5.0 < fc < 125.0
    assert auto_cutoff(np.ones(1000), fs) is None


def test_sign_changes_hysteresis():
    x = np.array([1, 1, 0.01, -0.01, 0.01, -1, -1, -0.01, 0.01, 1.0])
    ev = sign_changes(x, 0.5)
    assert list(ev) == [3, 8]


def test_from_arrays_checks():
    t = np.arange(50) * 1e-3
    cols = dict(
        base_speed=np.ones(50),
        load_torque=np.zeros(50),
        base_torque=np.zeros(50),
        follower_speed=np.ones(50),
    )
    m = Measurement.from_arrays("simple_gear", t, **cols)
    assert m.n == 50 and m.dt == pytest.approx(1e-3)
    bad = dict(cols, base_torque=np.r_[np.zeros(49), np.nan])
    with pytest.raises(MeasurementError, match="base_torque"):
        Measurement.from_arrays("simple_gear", t, **bad)
    with pytest.raises(MeasurementError, match="follower_speed"):
        Measurement.from_arrays(
            "simple_gear", t, **{k: v for k, v in cols.items() if k != "follower_speed"}
        )


def test_load_measurement_errors_name_the_place(tmp_path):
    f = tmp_path / "m.csv"
    f.write_text(
        "time,pinion_speed,load_force,pinion_torque,rack_velocity\n"
        + "".join(f"{i * 1e-3},1,0,0.1,0.05\n" for i in range(30))
    )
    assert load_measurement(f, "rack_pinion").n == 30
    with pytest.raises(MeasurementError) as exc:
        load_measurement(f, "simple_gear")
    assert exc.value.column == "base_speed" and exc.value.line == 1
    with pytest.raises(MeasurementError, match="no such file"):
        load_measurement(tmp_path / "x.csv", "rack_pinion")
    f.write_text("")
    with pytest.raises(MeasurementError, match="empty"):
        load_measurement(f, "rack_pinion")


def test_regimes_cover_the_physics():
    meas = measurement("simple_gear", ("coulomb_friction",))
    names = {r.name for r in segment(meas)}
    assert {
        "direction_reversal",
        "torque_reversal",
        "low_speed",
        "high_speed",
        "low_load",
        "high_load",
        "driving",
        "overrunning",
        "temperature_low",
        "temperature_mid",
        "temperature_high",
    } <= names
    for r in segment(meas):
        assert 0.0 < r.fraction < 1.0, r.name


def test_failing_regime_stands_out():
    # backlash: the error sits right after torque reversals
    c = compare(base_model("rack_pinion"), measurement("rack_pinion", ("backlash",)))
    failing = [r["regime"] for r in c.failing_regimes]
    assert "torque_reversal" in failing
    # a constant offset fails nowhere in particular
    c = compare(base_model("rack_pinion"), measurement("rack_pinion", ("load_offset",)))
    assert "torque_reversal" not in [r["regime"] for r in c.failing_regimes]


def test_effect_table():
    assert EFFECT_NAMES == CONTRACT_EFFECTS
    gear, rack = base_model("simple_gear"), base_model("rack_pinion")
    # without a teeth count the ripple is not a candidate, and says why
    usable, skipped = applicable_effects(gear)
    assert [e.name for e in usable] == [n for n in EFFECT_NAMES if n != "torque_ripple"]
    assert "ripple_mesh_teeth" in skipped["torque_ripple"]
    assert [e.name for e in applicable_effects(rack)[0]] == [
        n for n in EFFECT_NAMES if n not in ("load_dependent_efficiency", "torque_ripple")
    ]
    # the teeth count given in [rig], or the rack's tooth parameters
    toothed = gear.replace(rig_params={"ripple_mesh_teeth": 20})
    assert "torque_ripple" in [e.name for e in applicable_effects(toothed)[0]]
    rack_teeth = rack.replace(
        block_params={"parameterization": "tooth_parameters", "teeth_count": 12, "spacing": 0.01}
    )
    assert "torque_ripple" in [e.name for e in applicable_effects(rack_teeth)[0]]
    # the C rig refuses a compliant shaft with backlash: neither is offered with the other
    lash = gear.replace(block_params={"backlash_enabled": True, "linear_backlash": 1e-3})
    assert "rigid mesh" in applicable_effects(lash)[1]["compliance"]
    shaft = gear.replace(rig_params={"base_inertia": 0.01, "compliance_stiffness": 100.0})
    assert "rigid base shaft" in applicable_effects(shaft)[1]["backlash"]
    with pytest.raises(EffectError, match="unknown effect 'foo'"):
        get_effect("foo")
    with pytest.raises(EffectError, match="does not apply"):
        get_effect("load_dependent_efficiency", rack)
    with pytest.raises(EffectError, match="already"):
        get_effect(
            "meshing_efficiency",
            gear.replace(block_params={"friction_model": "constant_efficiency"}),
        )
