"""Defaults of the Python classes: read from the C core, equal to the seeds'
values (docs/physics.md section 9) and to the proposals in brackets there."""

import math

import pytest

import gearsim


def test_rack_pinion_defaults_match_the_seed():
    d = gearsim.RackPinion.defaults()
    assert d["parameterization"] == "pinion_radius"
    assert d["pinion_radius"] == pytest.approx(0.100)  # 100 mm
    assert d["teeth_count"] == 20
    assert d["spacing"] == pytest.approx(0.005)  # 5 mm
    assert d["rack_directionality"] == "positive"
    assert d["friction_model"] == "none"
    assert d["efficiency_const"] == 0.8
    assert d["temperature_vector"] == [280.0, 300.0, 320.0]
    assert d["efficiency_vector"] == [0.95, 0.90, 0.85]
    assert d["power_threshold"] == pytest.approx(1e-3)  # 1 mW
    assert d["pinion_viscous_coefficient"] == 0.0
    assert d["rack_viscous_coefficient"] == 0.0
    assert d["thermal_mass"] == 50.0
    assert d["initial_temperature"] == 300.0


def test_rack_pinion_radius_from_tooth_parameters():
    rp = gearsim.RackPinion(parameterization="tooth_parameters")
    assert rp.radius == pytest.approx(20 * 0.005 / (2 * math.pi))  # 15.915 mm
    assert gearsim.RackPinion().radius == pytest.approx(0.1)


def test_simple_gear_defaults():
    d = gearsim.SimpleGear.defaults()
    assert d["teeth_ratio"] == 2.0
    assert d["output_shaft_rotates"] == "opposite"
    assert d["friction_model"] == "none"
    assert d["loss_smoothing"] == "passive"
    assert d["viscous_coefficients"] == [0.0, 0.0]
    assert d["efficiency_const"] == 0.98
    assert d["power_threshold"] == pytest.approx(1e-3)
    assert d["idle_torque"] == pytest.approx(0.01)
    assert d["nominal_output_torque"] == 1.0
    assert d["efficiency_nominal"] == 0.95
    assert d["speed_threshold"] == pytest.approx(0.01)
    assert d["temperature_vector"] == [280.0, 300.0, 320.0]
    assert d["efficiency_vector"] == [0.95, 0.90, 0.85]
    assert d["load_vector"] == [0.0, 50.0, 100.0]
    matrix = d["efficiency_matrix"]
    assert len(matrix) == 3 and all(len(row) == 3 for row in matrix)
    assert d["backlash_enabled"] is False
    assert d["hard_stop_model"] == "smooth"
    assert d["linear_backlash"] == pytest.approx(1e-3)
    assert d["base_radius"] == pytest.approx(0.1)
    assert d["transition_region"] == pytest.approx(1e-4)
    assert d["stiffness"] == 1e6
    assert d["damping"] == 1e3
    assert d["initial_backlash_position"] == 0.0
    assert d["contact_no_pull"] is True
    assert d["contact_lock_enabled"] is False
    assert d["thermal_mass"] == 50.0
    assert d["initial_temperature"] == 300.0


def test_every_documented_parameter_has_a_default():
    sg = gearsim.SimpleGear.defaults()
    rp = gearsim.RackPinion.defaults()
    assert set(sg) == set(gearsim.SimpleGear.parameter_names())
    assert set(rp) == set(gearsim.RackPinion.parameter_names())
    assert "base_radius" in sg and "base_radius" not in rp


def test_rig_defaults():
    g = gearsim.Rig.defaults("simple_gear")
    r = gearsim.Rig.defaults("rack_pinion")
    assert "follower_inertia" in g and "rack_mass" not in g
    assert "rack_mass" in r and "follower_inertia" not in r
    for d in (g, r):
        assert d["thermal_resistance"] is None  # adiabatic
        assert d["base_drive"] == "speed"
        assert d["base_inertia"] == 0.0
        assert d["load_coulomb_speed_threshold"] == pytest.approx(1e-3)
        assert d["accel_filter_time_constant"] == 0.0
        assert d["contact_substeps"] == 0
        assert d["load_coulomb_friction"] == 0.0
        assert d["load_offset"] == 0.0
        assert d["initial_base_speed"] == 0.0
        assert d["ambient_temperature"] == pytest.approx(293.15)


def test_defaults_build_valid_objects():
    gear = gearsim.SimpleGear()
    rack = gearsim.RackPinion()
    assert gear.params == gearsim.SimpleGear.defaults()
    assert gear.given_params == {}
    assert gear.teeth_ratio == 2.0
    assert rack.pinion_radius == pytest.approx(0.1)
    rig = gearsim.GearRig()
    assert rig.dt == 1e-3 and rig.kind == "simple_gear" and rig.base_drive == "speed"
    assert gearsim.RackRig().kind == "rack_pinion"


def test_constants_come_from_the_compiled_library():
    assert gearsim.TABLE_MAX == 10
    assert gearsim.MAX_SUBSTEPS == 64
    assert gearsim.__version__ == "0.1.0"
    assert len(gearsim.INPUT_NAMES) == 5
    assert len(gearsim.OUTPUT_NAMES) == 15
