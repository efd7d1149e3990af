"""The rig terms, seen from Python (docs/physics.md 11,
"Effects of real rigs"): Stribeck friction, the compliant base shaft
and the base-side torque ripple.

These tests prove that each key reaches the C rig with its unit converted:
every expected number is derived by hand from the physics (rigid-body
mechanics, the spring's equilibrium, the ripple formula), with the
parameters given in units other than SI where that makes a wrong conversion
show.
"""

import math

import numpy as np
import pytest

import gearsim
from gearsim.cli import main

DT = 1e-3  # s, the rigs' default step

# ---------------------------------------------------------------- Stribeck


def _free_rack(**extra):
    """A lossless rack rig whose pinion is torque-driven with no motor torque,
    so the rack moves freely under its load: r_P = 20 mm, rack 2 kg, pinion
    4e-4 kg*m^2, i.e. an effective mass 2 + 4e-4/0.02^2 = 3 kg at the rack."""
    return gearsim.RackRig(
        friction_model="none",
        pinion_radius="20 mm",
        rack_mass="2 kg",
        base_inertia="4e-4 kg*m**2",
        base_drive="torque",
        load_coulomb_friction="0.4 kN",
        load_breakaway_friction="1.2 kN",
        load_stribeck_speed="1 mm/s",
        **extra,
    )


RACK_MASS_EFF = 3.0  # kg
RACK_F_C, RACK_F_BRK = 400.0, 1200.0  # N


def test_rack_breakaway_holds_below_and_breaks_above():
    rig = _free_rack()
    assert rig.params["load_breakaway_friction"] == RACK_F_BRK
    assert rig.params["load_stribeck_speed"] == pytest.approx(1e-3)
    held = rig.run(base_torque=np.zeros(200), load=RACK_F_BRK - 10.0)
    assert np.all(held.follower_speed == 0.0) and held.follower_position[-1] == 0.0

    moving = _free_rack().run(base_torque=np.zeros(200), load=RACK_F_BRK + 10.0)
    # First step: the friction level is the breakaway one (the step starts at
    # rest), so v1 = (L - F_brk)/m_eff*dt.
    assert moving.follower_speed[0] == pytest.approx(10.0 / RACK_MASS_EFF * DT, rel=1e-9)
    # Far above v_S the hump is gone: a = (L - F_C)/m_eff = 270 m/s^2.
    accel = np.diff(moving.follower_speed[100:])
    assert accel / DT == pytest.approx((RACK_F_BRK + 10.0 - RACK_F_C) / RACK_MASS_EFF, rel=1e-9)


def test_gear_breakaway_in_newton_metres_strings():
    """Gear rig, teeth ratio 2 (follower per base a = -1/2): the base inertia
    seen at the follower is J_B/a^2, so J_eff = 0.05 + 4*1e-3 = 0.054 kg*m^2."""
    kw = dict(
        friction_model="none",
        teeth_ratio=2,
        follower_inertia=0.05,
        base_inertia="1e-3 kg*m**2",
        base_drive="torque",
        load_coulomb_friction="1000 N*mm",
        load_breakaway_friction="3 N*m",
        load_stribeck_speed="0.6 rpm",
    )
    rig = gearsim.GearRig(**kw)
    assert rig.params["load_stribeck_speed"] == pytest.approx(0.6 * 2 * math.pi / 60)
    held = rig.run(base_torque=np.zeros(100), load=2.99)
    assert np.all(held.follower_speed == 0.0)
    moving = gearsim.GearRig(**kw).run(base_torque=np.zeros(400), load=3.05)
    assert moving.follower_speed[0] == pytest.approx(0.05 / 0.054 * DT, rel=1e-9)
    accel = np.diff(moving.follower_speed[300:]) / DT
    assert accel == pytest.approx((3.05 - 1.0) / 0.054, rel=1e-9)


# ---------------------------------------------------------------- compliance

K_SHAFT = 2.0 * 180.0 / math.pi  # N*m/rad: "2 N*m/deg"
J_BASE, J_FOLLOWER, GEAR_A = 1e-3, 0.05, -0.5  # kg*m^2, kg*m^2, follower per base
J_EFF = J_BASE + GEAR_A**2 * J_FOLLOWER  # inertia at the base shaft


def _compliant_gear(damping):
    return gearsim.GearRig(
        friction_model="none",
        teeth_ratio=2,
        follower_inertia=J_FOLLOWER,
        base_inertia=f"{J_BASE * 1e3} g*m**2",
        compliance_stiffness="2 N*m/deg",
        compliance_damping=damping,
    )


def test_compliant_shaft_static_deflection_under_a_held_load():
    """Drive held at rest, load L on the follower: the mesh puts a*L on the
    base gear, the spring balances it, k*phi + a*L = 0. Then phi = -a*L/k, the
    base gear turns a*L/k, the follower a^2*L/k, and the drive shaft carries
    k*phi = -a*L."""
    load = 1.5  # N*m
    rig = _compliant_gear("1.2 N*m*s/rad")
    assert rig.params["compliance_stiffness"] == pytest.approx(K_SHAFT, rel=1e-12)
    # omega_n*dt = 0.092 <= 0.2: one sub-step is enough.
    assert rig.compliance_substeps == 1
    assert rig.compliance_h_omega_n == pytest.approx(math.sqrt(K_SHAFT / J_EFF) * DT, rel=1e-12)
    assert rig.info["compliance_substeps"] == 1 and rig.info["follower_per_base"] == GEAR_A
    out = rig.run(base_speed=np.zeros(3000), load=load)
    assert out.base_angle[-1] == pytest.approx(GEAR_A * load / K_SHAFT, rel=1e-9)
    assert out.follower_position[-1] == pytest.approx(GEAR_A**2 * load / K_SHAFT, rel=1e-9)
    assert out.base_torque[-1] == pytest.approx(-GEAR_A * load, rel=1e-9)
    assert rig.state["shaft_twist"] == pytest.approx(-GEAR_A * load / K_SHAFT, rel=1e-9)


def test_compliant_shaft_rings_at_its_natural_frequency_and_decays():
    """A load step on a lightly damped shaft: the shaft torque rings at
    omega_d = sqrt(omega_n^2 - sigma^2), sigma = c/(2*J_eff) (physics.md 11.4;
    the midpoint rule lowers the frequency by 0.07 % at h*omega_n = 0.09), and
    successive peaks of the same sign fall by exp(-sigma*2*pi/omega_d)."""
    damping = 0.05  # N*m*s/rad, given in N*m*s/deg to check that conversion too
    rig = _compliant_gear(f"{damping * math.pi / 180} N*m*s/deg")
    assert rig.params["compliance_damping"] == pytest.approx(damping, rel=1e-12)
    load = 1.0
    out = rig.run(base_speed=np.zeros(1500), load=load)
    swing = out.base_torque - (-GEAR_A * load)
    omega_n = math.sqrt(K_SHAFT / J_EFF)
    sigma = damping / (2 * J_EFF)
    omega_d = math.sqrt(omega_n**2 - sigma**2)
    # upward zero crossings, interpolated between samples
    up = np.flatnonzero((swing[:-1] < 0) & (swing[1:] >= 0))
    times = (up + swing[up] / (swing[up] - swing[up + 1])) * DT
    period = np.mean(np.diff(times))
    assert 2 * math.pi / period == pytest.approx(omega_d, rel=2e-3)
    peaks = [swing[a:b].max() for a, b in zip(up[:-1], up[1:], strict=True)]
    ratios = np.array(peaks[1:]) / np.array(peaks[:-1])
    assert np.mean(ratios) == pytest.approx(math.exp(-sigma * 2 * math.pi / omega_d), rel=5e-3)


# ---------------------------------------------------------------- ripple


@pytest.mark.parametrize("block", ["simple_gear", "rack_pinion"])
def test_ripple_torque_at_the_steps_mid_angle(block):
    """Base held at a constant speed w from rest at angle 0: step k (k = 1..n)
    turns the base from (k-1)*w*dt to k*w*dt, and the rig evaluates the
    ripple at the mid angle theta = (k - 1/2)*w*dt. Against the same rig
    without ripple, base_torque gains
    A1 cos(theta + phi1) + A2 cos(2 theta + phi2)
    + M1 cos(Z theta + psi1) + M2 cos(2 Z theta + psi2).
    """
    speed, n = 7.0, 400  # rad/s (about 0.45 rev), steps
    if block == "simple_gear":
        common = dict(friction_model="none", follower_inertia=0.05)
    else:
        common = dict(friction_model="none", rack_mass=2.0, pinion_radius="20 mm")
    ripple = dict(
        ripple_revolution_amplitude=["300 N*mm", 0.1],
        ripple_revolution_phase=["30 deg", 0.4],
        ripple_mesh_amplitude=["5 N*cm", "0.02 N*m"],
        ripple_mesh_phase=[0.0, "-90 deg"],
        ripple_mesh_teeth=17,
    )
    make = gearsim.GearRig if block == "simple_gear" else gearsim.RackRig
    plain = make(**common).run(base_speed=np.full(n, speed), load=0.0)
    rig = make(**common, **ripple)
    rippled = rig.run(base_speed=np.full(n, speed), load=0.0)
    assert rig.params["ripple_mesh_amplitude"] == pytest.approx([0.05, 0.02])
    theta = (np.arange(1, n + 1) - 0.5) * speed * DT
    expected = (
        0.3 * np.cos(theta + math.pi / 6)
        + 0.1 * np.cos(2 * theta + 0.4)
        + 0.05 * np.cos(17 * theta)
        + 0.02 * np.cos(34 * theta - math.pi / 2)
    )
    np.testing.assert_allclose(rippled.base_torque - plain.base_torque, expected, atol=1e-12)
    np.testing.assert_allclose(rippled.base_angle, np.arange(1, n + 1) * speed * DT, rtol=1e-12)


# ---------------------------------------------------------------- parameters

NEW_KEYS = {
    "load_breakaway_friction": 3.0,
    "load_stribeck_speed": 0.02,
    "compliance_stiffness": 500.0,
    "compliance_damping": 0.3,
    "base_inertia": 2e-3,
    "ripple_revolution_amplitude": [0.2, 0.05],
    "ripple_revolution_phase": [0.1, -1.0],
    "ripple_mesh_amplitude": [0.01, 0.0],
    "ripple_mesh_phase": [0.5, 0.0],
    "ripple_mesh_teeth": 23,
}


def test_defaults_are_off():
    for block in ("simple_gear", "rack_pinion"):
        d = gearsim.Rig.defaults(block)
        assert d["load_breakaway_friction"] == 0.0 and d["load_stribeck_speed"] == 0.01
        assert d["compliance_stiffness"] == 0.0 and d["compliance_damping"] == 0.0
        for key in ("amplitude", "phase"):
            assert d[f"ripple_revolution_{key}"] == [0.0, 0.0]
            assert d[f"ripple_mesh_{key}"] == [0.0, 0.0]
        assert d["ripple_mesh_teeth"] == 0
    info = gearsim.GearRig().info
    assert info["compliance_substeps"] == 1 and info["compliance_h_omega_n"] == 0.0
    assert "shaft_twist" in gearsim.GearRig().state


def test_model_file_round_trip_with_the_new_keys(tmp_path):
    model = gearsim.Model("simple_gear", {"teeth_ratio": 3.0}, NEW_KEYS)
    path = tmp_path / "effects.toml"
    model.save(path)
    again = gearsim.Model.load(path)
    assert again == model
    assert again.rig_params == NEW_KEYS
    text = path.read_text()
    assert "ripple_mesh_teeth = 23" in text
    # unit strings in a file: the rack's driven-side keys are forces and speeds
    path.write_text(
        '[rig]\nblock = "rack_pinion"\nload_coulomb_friction = "10 N"\n'
        'load_breakaway_friction = "0.04 kN"\nload_stribeck_speed = "13 mm/s"\n'
        'ripple_revolution_phase = ["90 deg", "0.5 rad"]\n'
    )
    rack = gearsim.Model.load(path)
    assert rack.rig_params["load_breakaway_friction"] == pytest.approx(40.0)
    assert rack.rig_params["load_stribeck_speed"] == pytest.approx(0.013)
    assert rack.rig_params["ripple_revolution_phase"] == pytest.approx([math.pi / 2, 0.5])


@pytest.mark.parametrize(
    ("params", "key", "status"),
    [
        (
            {"load_coulomb_friction": 2.0, "load_breakaway_friction": 1.0},
            "load_breakaway_friction",
            "GS_E_BREAKAWAY",
        ),
        ({"load_breakaway_friction": 1.0, "load_stribeck_speed": 0.0}, "load_stribeck_speed", None),
        ({"compliance_stiffness": 100.0, "base_inertia": -1.0}, "base_inertia", "GS_E_NEGATIVE"),
        (
            {"compliance_stiffness": 100.0, "base_inertia": 1e-3, "base_drive": "torque"},
            "compliance_stiffness",
            "GS_E_COMBINATION",
        ),
        ({"compliance_damping": -1.0}, "compliance_damping", None),
        ({"ripple_mesh_amplitude": [0.1, 0.0]}, "ripple_mesh_teeth", "GS_E_NOT_POSITIVE"),
        ({"ripple_revolution_amplitude": [0.1]}, "ripple_revolution_amplitude", None),
        ({"ripple_mesh_phase": [0.0, 1.0, 2.0]}, "ripple_mesh_phase", None),
        ({"ripple_mesh_teeth": 2.5}, "ripple_mesh_teeth", None),
        ({"load_stribeck_speed": "3 N*m"}, "load_stribeck_speed", None),
    ],
)
def test_bad_values_name_the_key(params, key, status):
    with pytest.raises(gearsim.GearsimError) as info:
        gearsim.GearRig(**params)
    assert info.value.parameter == key and str(info.value).startswith(key)
    if status:
        assert info.value.status == status


def test_compliance_with_backlash_is_refused():
    with pytest.raises(gearsim.ParameterError) as info:
        gearsim.GearRig(backlash_enabled=True, compliance_stiffness=100.0, base_inertia=1e-3)
    assert info.value.parameter == "compliance_stiffness"
    assert info.value.status == "GS_E_COMBINATION"


def test_cli_exits_2_naming_the_bad_key_of_a_model_file(tmp_path, capsys):
    data = tmp_path / "run.csv"
    rows = [f"{i * DT:.3f},{1 + i % 3},0.5,0.2,{-(1 + i % 3) / 3:.4f}" for i in range(50)]
    data.write_text("time,base_speed,load_torque,base_torque,follower_speed\n" + "\n".join(rows))
    model = tmp_path / "model.toml"
    model.write_text('[rig]\nblock = "simple_gear"\nripple_mesh_amplitude = [0.1, 0.2, 0.3]\n')
    assert main(["compare", str(data), "--model", str(model)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0
    assert "model.toml" in err and "ripple_mesh_amplitude" in err and "2 values" in err
