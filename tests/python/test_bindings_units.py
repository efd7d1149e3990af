"""Unit strings of the seeds' unit lists, converted by pint to each parameter's
SI unit; plain numbers are SI; temperatures are absolute."""

import math

import pytest

import gearsim

SG = gearsim.SimpleGear
RP = gearsim.RackPinion


@pytest.mark.parametrize(
    ("cls", "name", "text", "si"),
    [
        (RP, "pinion_radius", "100 mm", 0.1),
        (RP, "pinion_radius", "10 cm", 0.1),
        (RP, "pinion_radius", "2 in", 0.0508),
        (RP, "spacing", "5000 um", 0.005),
        (SG, "speed_threshold", "3000 rpm", 3000 * 2 * math.pi / 60),
        (SG, "speed_threshold", "90 deg/s", math.pi / 2),
        (SG, "speed_threshold", "0.5 rad/s", 0.5),
        (SG, "initial_temperature", "80 degC", 353.15),
        (SG, "initial_temperature", "212 degF", 373.15),
        (SG, "initial_temperature", "540 degR", 300.0),
        (SG, "initial_temperature", "300 K", 300.0),
        (SG, "power_threshold", "0.5 kW", 500.0),
        (SG, "power_threshold", "1 mW", 1e-3),
        (SG, "power_threshold", "20 uW", 2e-5),
        (SG, "power_threshold", "1 HP_DIN", 735.49875),
        (SG, "idle_torque", "5 mN*m", 5e-3),
        (SG, "nominal_output_torque", "1 lbf*ft", 1.3558179483314004),
        (SG, "stiffness", "1 lbf/in", 175.126835246),
        (SG, "damping", "1 kg/s", 1.0),
        (SG, "damping", "2 N/(m/s)", 2.0),
        (SG, "thermal_mass", "0.05 kJ/K", 50.0),
        (SG, "efficiency_const", "95 %", 0.95),
        (RP, "pinion_viscous_coefficient", "1 ft*lbf/(rad/s)", 1.3558179483314004),
        (RP, "rack_viscous_coefficient", "1 lbf/(ft/s)", 14.593902937),
    ],
)
def test_unit_string(cls, name, text, si):
    assert cls(**{name: text}).params[name] == pytest.approx(si, rel=1e-9)


def test_vectors_with_units():
    gear = SG(temperature_vector=["7 degC", "27 degC", "47 degC"])
    assert gear.temperature_vector == pytest.approx([280.15, 300.15, 320.15])
    gear = SG(temperature_vector="[280, 300, 320] K", load_vector="[0, 50, 100] mN*m")
    assert gear.load_vector == pytest.approx([0.0, 0.05, 0.1])
    gear = SG(viscous_coefficients=["1 mN*m/(rad/s)", 0.002])
    assert gear.viscous_coefficients == pytest.approx([1e-3, 2e-3])


def test_rig_parameters_with_units():
    rig = gearsim.GearRig(
        follower_inertia="500 kg*cm^2",
        load_coulomb_speed_threshold="6 deg/s",
        ambient_temperature="25 degC",
        accel_filter_time_constant="5 ms",
    )
    p = rig.params
    assert p["follower_inertia"] == pytest.approx(0.05)
    assert p["load_coulomb_speed_threshold"] == pytest.approx(math.pi / 30)
    assert p["ambient_temperature"] == pytest.approx(298.15)
    assert p["accel_filter_time_constant"] == pytest.approx(5e-3)
    rack = gearsim.RackRig(load_coulomb_speed_threshold="1 mm/s", load_offset="-9.81 N")
    assert rack.params["load_coulomb_speed_threshold"] == pytest.approx(1e-3)


@pytest.mark.parametrize(
    ("name", "text"),
    [
        ("pinion_radius", "3 kg"),  # wrong dimension
        ("pinion_radius", "0.1"),  # a string without a unit for a dimensional parameter
        ("pinion_radius", "12 parsecs_per_fortnight"),  # unknown unit
        ("pinion_radius", "big"),  # not a number
        ("initial_temperature", "10 delta_degC"),  # a difference, not a temperature
    ],
)
def test_bad_unit_strings_name_the_parameter(name, text):
    with pytest.raises(gearsim.ParameterError) as e:
        RP(**{name: text})
    assert e.value.parameter == name and name in str(e.value)


def test_units_table_declares_each_parameter_once():
    units = gearsim.param_units("simple_gear")
    assert units["teeth_ratio"] == ""
    assert units["initial_temperature"] == "K"
    assert units["follower_inertia"] == "kg*m**2"
    assert units["load_coulomb_friction"] == "N*m"
    rack = gearsim.param_units("rack_pinion")
    assert rack["rack_mass"] == "kg"
    assert rack["load_coulomb_friction"] == "N"
    assert rack["load_coulomb_speed_threshold"] == "m/s"
    assert rack["pinion_radius"] == "m"
